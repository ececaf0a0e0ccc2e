"""The add-on's batch commands, run headless by cli.py (blender -b -P cli.py -- --open
scene.blend COMMAND ...) once the add-on is enabled: arguments.py parses, commands.py runs, and
main() opens the .blend and turns errors into the messages and exit statuses README.md lists."""

from __future__ import annotations

import sys

from ...core import native as native_loader
from ...core.errors import InputError
from .arguments import build_parser
from .scene_access import open_blend
from .status import EXIT_BAD_INPUT, EXIT_CANCELLED, EXIT_FAILURE, BatchError


def _arguments(argv) -> list:
    return argv[argv.index("--") + 1:] if "--" in argv else []


def main(argv=None) -> int:
    """Runs the command that argv (Blender's, with the command after "--") names; the exit status."""
    args = build_parser().parse_args(_arguments(sys.argv if argv is None else argv))
    try:
        native = native_loader.load()
    except ImportError as error:
        print(f"lfprobe: error: {error}", file=sys.stderr)
        return EXIT_FAILURE
    try:
        if args.open:
            open_blend(args.open)
        return args.run(args)
    except BatchError as error:
        print(f"lfprobe: error: {error}", file=sys.stderr)
        return error.status
    # Every error the add-on reports about its input (GridError, TraceSetupError, ...).
    except (InputError, native.InputError, FileNotFoundError) as error:
        print(f"lfprobe: error: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except native.Cancelled:
        print("lfprobe: cancelled", file=sys.stderr)
        return EXIT_CANCELLED
    except (native.NativeIOError, OSError) as error:
        print(f"lfprobe: error: {error}", file=sys.stderr)
        return EXIT_FAILURE
