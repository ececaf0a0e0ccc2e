"""Bakes on a Dask cluster (core/cluster_bake.py): a local cluster of 2 worker processes gives
the set a local bake writes, byte for byte, even when a worker is killed mid-bake; cancelling
leaves nothing behind; a scheduler that cannot be reached is an error (exit 2) that writes
nothing."""

import logging
import os
import signal
import time

import pytest

from conftest import run_cli

distributed = pytest.importorskip("distributed", reason="Dask's distributed package is not installed")

from lfprobe.core import cluster_bake, native  # noqa: E402
from lfprobe.core.cli.main import main as cli_main  # noqa: E402
from lfprobe.core.pipeline import BakeOptions, ProbePlacementSpec, bake_from_scans  # noqa: E402

GRID = dict(grid_min=[-1.0, -1.0, 0.5], grid_max=[1.0, 1.0, 1.5], counts=[3, 2, 1])


@pytest.fixture(scope="module")
def scan(shared_data):
    return os.path.join(shared_data, "scans", "pumpA_xyzrgb.xyz")


@pytest.fixture(scope="module")
def local_set(scan, tmp_path_factory):
    """The reference: the same bake in this process."""
    root = tmp_path_factory.mktemp("local")
    folder = str(root / "set")
    bake_from_scans([scan], folder, ProbePlacementSpec(**GRID), BakeOptions(resolution=128),
                    cache_dir=str(root / "cache"))
    return folder


@pytest.fixture
def local_cluster():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None, silence_logs=logging.ERROR)
    client = distributed.Client(cluster, set_as_default=False)
    yield cluster, client
    client.close()
    cluster.close()


def assert_same_set(expected: str, actual: str) -> None:
    names = sorted(os.listdir(expected))
    assert sorted(os.listdir(actual)) == names
    assert len(names) == 8  # six probes, their known space and the manifest
    for name in names:
        with open(os.path.join(expected, name), "rb") as a, open(os.path.join(actual, name), "rb") as b:
            assert a.read() == b.read(), name


def leftovers(root) -> list:
    """Files and folders a bake must not leave: staging folders and temporaries."""
    found = []
    for folder, dirs, files in os.walk(root):
        found += [os.path.join(folder, n) for n in dirs + files if n.endswith(".partial") or ".tmp." in n]
    return found


def test_two_workers_bake_the_local_set_bit_for_bit(scan, local_set, tmp_path):
    out = tmp_path / "set"
    code = cli_main(["bake", "--scan", scan, "--grid-min", "-1", "-1", "0.5", "--grid-max", "1", "1", "1.5",
                     "--counts", "3", "2", "1", "--res", "128", "--out", str(out), "--cache", str(tmp_path / "cache"),
                     "--workers", "2", "--probes-per-task", "2", "--quiet"])
    assert code == 0
    assert_same_set(local_set, str(out))
    assert leftovers(tmp_path) == []
    # The client prepared the cloud into the cache and wrote it as a spatial cloud, which the
    # tasks read in parts instead of loading the cloud.
    assert len(list((tmp_path / "cache").glob("prepared-*.lfpprep"))) == 1
    assert len(list((tmp_path / "cache").glob("spatial-*.lfpspatial"))) == 1


def test_tasks_that_load_the_whole_cloud_bake_the_same_set(scan, local_set, tmp_path, local_cluster):
    cluster, _client = local_cluster
    out = tmp_path / "set"
    summary = cluster_bake.bake_scans_on_cluster(
        [scan], str(out), ProbePlacementSpec(**GRID), BakeOptions(resolution=128),
        cache_dir=str(tmp_path / "cache"), scheduler=cluster.scheduler_address, probes_per_task=2,
        read_in_parts=False)
    assert summary["cluster"]["tasks_reading_in_parts"] == 0
    assert_same_set(local_set, str(out))


def test_workers_read_the_cloud_the_client_prepared(scan, tmp_path, local_cluster):
    cluster, _client = local_cluster
    summary = cluster_bake.bake_scans_on_cluster(
        [scan], str(tmp_path / "set"), ProbePlacementSpec(**GRID), BakeOptions(resolution=64),
        cache_dir=str(tmp_path / "cache"), scheduler=cluster.scheduler_address, probes_per_task=3)
    figures = summary["cluster"]
    assert figures["workers_reading_the_prepared_cloud"] == figures["workers_used"] >= 1
    assert summary["hierarchy_seconds"] == 0.0
    # Every task read the spatial cloud in parts: some of its pages, never more than the file.
    assert figures["tasks_reading_in_parts"] == figures["tasks"] == 2
    assert 0 < figures["bytes_read_per_task"] <= figures["spatial_cloud_bytes"]


def test_a_worker_killed_mid_bake_still_gives_the_identical_set(scan, local_set, tmp_path, local_cluster):
    cluster, client = local_cluster
    killed = {}

    def kill_a_busy_worker(fraction, stage):
        # Without a cache the first tasks spend about half a second parsing the scan and
        # estimating normals (with one, the client prepares the cloud and the workers only read
        # it, too quickly to be caught): kill the process of a worker that holds a task then.
        if not killed:
            for address, tasks in client.processing().items():
                if tasks:
                    pid = client.run(os.getpid, workers=[address])[address]
                    os.kill(pid, signal.SIGKILL)
                    killed.update(address=address, pid=pid, tasks=list(tasks))
                    break
        return True

    out = tmp_path / "set"
    summary = cluster_bake.bake_scans_on_cluster(
        [scan], str(out), ProbePlacementSpec(**GRID), BakeOptions(resolution=128),
        cache_dir="", scheduler=cluster.scheduler_address, probes_per_task=3,
        progress=kill_a_busy_worker)
    assert killed, "no worker was busy to be killed"
    assert summary["probe_count"] == 6
    assert_same_set(local_set, str(out))
    assert leftovers(tmp_path) == []


@pytest.mark.parametrize("how", ["callback", "ctrl-c"])
def test_cancelling_leaves_no_manifest_and_no_temporaries(scan, tmp_path, how):
    def cancel_after_a_probe(fraction, stage):
        if fraction > 0:
            if how == "ctrl-c":
                raise KeyboardInterrupt
            return False
        return True

    out = tmp_path / "set"
    expected = KeyboardInterrupt if how == "ctrl-c" else native.cancelled_type()
    with pytest.raises(expected):
        cluster_bake.bake_scans_on_cluster(
            [scan], str(out), ProbePlacementSpec(**GRID), BakeOptions(resolution=128),
            cache_dir=str(tmp_path / "cache"), workers=2, progress=cancel_after_a_probe)
    time.sleep(0.5)  # anything a worker still wrote would be there by now
    assert not out.exists()
    assert leftovers(tmp_path) == []


def test_an_unreachable_scheduler_is_exit_2_and_writes_nothing(scan, tmp_path):
    out = tmp_path / "set"
    result = run_cli("bake", "--scan", scan, "--probe", "0", "0", "1", "--res", "32", "--out", out,
                     "--cache", tmp_path / "cache", "--scheduler", "tcp://127.0.0.1:9", timeout=120)
    assert result.returncode == 2, result.stderr
    assert "cannot reach the Dask scheduler at 'tcp://127.0.0.1:9'" in result.stderr
    assert "Traceback" not in result.stderr
    assert not out.exists()
    assert leftovers(tmp_path) == []


def test_cluster_options_are_checked_before_anything_runs(scan, tmp_path):
    both = run_cli("bake", "--scan", scan, "--probe", "0", "0", "1", "--out", tmp_path / "a",
                   "--scheduler", "tcp://127.0.0.1:9", "--workers", "2")
    assert both.returncode == 2 and "not both" in both.stderr
    auto = run_cli("bake", "--scan", scan, "--probe", "0", "0", "1", "--out", tmp_path / "b",
                   "--workers", "2", "--auto")
    assert auto.returncode == 2 and "one resolution" in auto.stderr
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()
