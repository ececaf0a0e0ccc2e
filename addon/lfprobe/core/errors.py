"""The errors lfprobe raises itself, under one base class, so that an entry point (the command
lines, an operator, the render engine) can tell a problem it reports from a bug it lets
through. The native module's InputError, NativeIOError and Cancelled are its own types."""

from __future__ import annotations


class LfprobeError(Exception):
    """Base of every error lfprobe raises itself; the message is what the user reads."""


class InputError(LfprobeError, ValueError):
    """Input that cannot be used as given (a file, a setting, an object in the scene); the
    message says what and how to fix it."""
