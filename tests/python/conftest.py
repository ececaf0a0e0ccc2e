import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "addon"))

SHARED_DATA = os.environ.get("LFPROBE_SHARED_DATA", os.path.join(ROOT, "..", "shared", "data"))


@pytest.fixture(scope="session")
def native():
    from lfprobe.core import native as native_loader

    return native_loader.load()


@pytest.fixture(scope="session")
def shared_data():
    if not os.path.isdir(SHARED_DATA):
        pytest.fail(f"test data not found at {SHARED_DATA} (set LFPROBE_SHARED_DATA)")
    return SHARED_DATA


def run_cli(*args, check=False, timeout=600):
    """Runs ./lfprobe with args; returns the CompletedProcess (text)."""
    result = subprocess.run(
        [os.path.join(ROOT, "lfprobe"), *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    if check and result.returncode != 0:
        raise AssertionError(f"lfprobe {' '.join(map(str, args))} failed:\n{result.stdout}\n{result.stderr}")
    return result
