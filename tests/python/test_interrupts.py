"""Ctrl-C and native jobs (Job.run): an interrupt that comes while the work can still stop
cancels it and nothing is written; one that comes when the work has already put its output in
place is not a cancel (the command said "cancelled", exit 130, with the new output there)."""

import os
import time

import pytest

from conftest import write_box_room_xyz


@pytest.fixture(scope="module")
def room_cloud(native, tmp_path_factory):
    path = tmp_path_factory.mktemp("room") / "room.xyz"
    write_box_room_xyz(str(path), 0.02)
    return native.load_scans([str(path)], scanners=[[0.0, 0.0, 1.2]], cache_dir="")


def test_ctrl_c_after_the_set_is_in_place_returns_the_result(native, room_cloud, tmp_path):
    folder = tmp_path / "set"
    job = native.start_bake_probe_set(room_cloud, str(folder), resolution=32, positions=[[0, 0, 1.2]])

    def interrupt_once_written(fraction, stage):
        deadline = time.monotonic() + 60
        while not (folder / "manifest.json").exists() and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(0.2)  # the job has ended by now: its last step is the swap into place
        raise KeyboardInterrupt

    summary = job.run(interrupt_once_written)
    assert summary["probe_count"] == 1
    assert sorted(os.listdir(folder)) == ["known_space.bin", "manifest.json", "probe_00000.exr"]


def test_ctrl_c_while_the_work_runs_cancels_it_and_writes_nothing(native, room_cloud, tmp_path):
    folder = tmp_path / "set"
    job = native.start_bake_probe_set(room_cloud, str(folder), resolution=1024,
                                      grid_min=[-1.5, -1.0, 0.5], grid_max=[1.5, 1.0, 2.0], counts=[4, 3, 3])

    def interrupt(fraction, stage):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        job.run(interrupt)
    assert not folder.exists()
    assert not (tmp_path / "set.partial").exists()
