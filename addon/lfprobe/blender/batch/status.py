"""Exit statuses of the batch commands and the error that carries one."""

from __future__ import annotations

from ...core.errors import LfprobeError

EXIT_OK, EXIT_FAILURE, EXIT_BAD_INPUT, EXIT_CANCELLED = 0, 1, 2, 130


class BatchError(LfprobeError):
    """A failure with its exit status; the message is what the user reads."""

    def __init__(self, message: str, status: int = EXIT_BAD_INPUT):
        super().__init__(message)
        self.status = status
