"""`lfprobe store`: how a baked probe set loads into memory (a manifest's "storage" is
decoded in core/probe_storage.py; the --storage options are in arguments.py)."""

from __future__ import annotations

import json

from .. import native
from ..probe_set import summarize
from ..probe_storage import describe
from .arguments import distance_step_help, finite_float

def _cmd_store(args) -> int:
    stored = native.load().set_probe_set_storage(args.folder, args.storage, distance_step=args.distance_step)
    info = summarize(args.folder)
    if args.json:
        print(json.dumps({"storage": stored, "memory_bytes": info["memory_bytes"]}, indent=2))
        return 0
    mib = 1024.0 * 1024.0
    print(f"{info['folder']}: loads as {describe(stored)}; {info['memory_bytes'] / mib:.2f} MiB in memory "
          f"with coarse levels ({info['memory_bytes_per_probe'] / mib:.2f} MiB per probe)")
    return 0


def add_parsers(sub) -> None:
    store = sub.add_parser("store", help="set how a baked probe set loads into memory")
    store.add_argument("folder", metavar="DIR")
    store.add_argument("storage", choices=["full", "compact"])
    store.add_argument("--distance-step", type=finite_float, default=0.0, metavar="M", help=distance_step_help())
    store.add_argument("--json", action="store_true")
    store.set_defaults(run=_cmd_store)
