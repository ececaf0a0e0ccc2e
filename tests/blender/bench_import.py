"""How long importing a scan into Blender takes (File › Import › Scan Cloud, headless):

    blender -b --factory-startup -P tests/blender/bench_import.py -- FILE [DISPLAY_LIMIT]

Prints the time of a first import (the native parse, then the scan object), of a second one
(the parse cache read instead), and of the native read alone, so that the Blender side
(subsample, mesh, colour attribute, modifier) is their difference. Not a test: it times."""

import os
import shutil
import sys
import tempfile
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import helpers  # noqa: E402  (after the path above)


def main() -> int:
    arguments = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    if not arguments:
        print(__doc__)
        return 2
    path = os.path.abspath(arguments[0])
    limit = int(arguments[1]) if len(arguments) > 1 else 2_000_000
    cache = tempfile.mkdtemp(prefix="lfprobe-bench-cache-")
    os.environ["LFPROBE_CACHE"] = cache
    try:
        helpers.enable_addon()
        pipeline = helpers.addon("core.pipeline")
        timings = {}
        for label in ("first import (parse + object)", "second import (cache + object)"):
            start = time.perf_counter()
            (obj,) = helpers.import_scans(path, display_limit=limit)
            timings[label] = time.perf_counter() - start
        start = time.perf_counter()
        cloud = pipeline.load_scans([path], cache_dir=cache)
        timings["native read from the cache alone"] = time.perf_counter() - start
        props = obj.lfprobe_scan
        print(f"\n{path}: {os.path.getsize(path) / 1e6:.0f} MB, {props.point_count:,} points, "
              f"{props.display_count:,} displayed (display limit {limit:,}); Blender {bpy.app.version_string}")
        for label, seconds in timings.items():
            print(f"  {label}: {seconds:.2f} s")
        blender_side = timings["second import (cache + object)"] - timings["native read from the cache alone"]
        print(f"  Blender side (subsample, mesh, colours, modifier): {blender_side:.2f} s")
        assert len(cloud) == props.point_count
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
