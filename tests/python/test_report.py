"""`./lfprobe report`: the tiny preset end to end on a generated room scene (every section of
the page, its figures in JSON and CSV, images embedded), scene-file errors, the Pareto front,
and mesh-baked probes reproducing the ground truth from their own centre."""

import csv
import json
import os
import re
import shutil

import pytest

from conftest import ROOT, report_scene_module, run_cli

from lfprobe.core import metrics

SECTIONS = ["definitions", "speed", "distance", "at_probe", "resolution", "images", "peers", "planning",
            "stability"]


@pytest.fixture(scope="module")
def scene_path(tmp_path_factory):
    return report_scene_module().write_scene(str(tmp_path_factory.mktemp("report_scene")))


@pytest.fixture(scope="module")
def tiny_report(scene_path, tmp_path_factory):
    out = tmp_path_factory.mktemp("report_out")
    result = run_cli("report", "--scene", scene_path, "--out", out, "--preset", "tiny", "--threads", "2",
                     timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    with open(out / "report.json", encoding="utf-8") as stream:
        data = json.load(stream)
    return out, data, result


def test_page_is_self_contained_and_has_every_section(tiny_report):
    out, data, _ = tiny_report
    page = (out / "report.html").read_text(encoding="utf-8")
    for section in SECTIONS:
        assert f'id="{section}"' in page, section
    sources = re.findall(r'src="([^"]*)"', page)
    assert len(sources) >= 15
    assert all(s.startswith("data:image/png;base64,") for s in sources)
    assert "http://" not in page and "https://" not in page
    for key, definition in metrics.DEFINITIONS.items():
        assert definition.replace("<", "&lt;").replace(">", "&gt;") in page or definition in page, key
    assert not os.path.exists(out / "work"), "the work folder is removed unless --keep-work"


def test_sweep_rows_carry_speed_error_memory_and_bake_time(tiny_report):
    out, data, _ = tiny_report
    rows = data["sweep"]
    # 2 scan densities × 2 resolutions × 2 bake variants + 2 mesh resolutions, two more trace
    # settings on the reference probe set (no coarse levels; the paper's first hit, nearest
    # texel), and compact storage on both resolutions of the densest splat + fill bake
    assert len(rows) == 2 * 2 * 2 + 2 + 2 + 2
    assert sum(r["storage"] == "compact" for r in rows) == 2
    for row in rows:
        assert row["ms_per_frame"] > 0 and row["rays_per_second"] > 0
        assert row["memory_bytes_per_probe"] > 0 and row["bake_seconds"] > 0
        assert 0 < row["psnr"] < 100 and 0 < row["ssim"] <= 1 and 0 <= row["flip"] <= 1
        n = row["resolution"]
        # the maps (radiance, distance, normal...) at least hold a float distance per texel
        assert row["memory_bytes_per_probe"] >= 4 * n * n
    assert any(r["pareto_front"] for r in rows)
    with open(out / "sweep.csv", encoding="utf-8") as stream:
        csv_rows = list(csv.DictReader(stream))
    assert len(csv_rows) == len(rows)
    assert {"setting", "ms_per_frame", "rays_per_second", "psnr", "ssim", "flip", "memory_bytes_per_probe",
            "bake_seconds", "pareto_front"} <= set(csv_rows[0])
    assert len(data["sweep_views"]) == len(rows) * len(data["scene"]["views"])
    for name in ("sweep_views.csv", "distance.csv", "walk.csv", "at_probe.csv", "peers.csv",
                 "stability.csv", "ground_truth.csv", "planning_resolution.csv", "planning_walk.csv",
                 "planning_iterations.csv"):
        assert (out / name).stat().st_size > 100, name


def test_mesh_probes_beat_scan_probes_and_splatting_beats_points_only_at_high_resolution(tiny_report):
    _, data, _ = tiny_report
    default = [r for r in data["sweep"] if r["trace"].startswith("default")]
    best_mesh = max(r["psnr"] for r in default if r["source"] == "mesh")
    best_scan = max(r["psnr"] for r in default if r["source"] == "scan")
    assert best_mesh > best_scan
    for step in {r["scan_step_deg"] for r in default if r["source"] == "scan"}:
        top = max(r["resolution"] for r in default)
        by_bake = {r["bake"]: r for r in default if r["scan_step_deg"] == step and r["resolution"] == top}
        assert by_bake["splat + fill"]["hole_rate"] < by_bake["points only"]["hole_rate"]


def test_reference_trace_is_timed_against_embree_on_the_same_rays(tiny_report):
    out, data, _ = tiny_report
    rows = data["trace_against_embree"]
    assert [r["view"] for r in rows] == [v["name"] for v in data["scene"]["views"]]
    for r in rows:
        assert r["trace_rays_per_second"] > 0 and r["embree_rays_per_second"] > 0
        assert r["embree_packet"] in (4, 8, 16)
        assert r["trace_over_embree"] == pytest.approx(r["trace_rays_per_second"] / r["embree_rays_per_second"])
        assert r["trace_over_embree_packets"] == pytest.approx(
            r["trace_rays_per_second"] / r["embree_packet_rays_per_second"])
        assert r["texels_per_ray"] >= 1 and r["probes_per_ray"] >= 1 and r["distance_to_nearest_probe"] >= 0
        assert r["trace_from_answer_rays_per_second"] > 0
        assert r["trace_from_answer_over_embree"] == pytest.approx(
            r["trace_from_answer_rays_per_second"] / r["embree_rays_per_second"])
        assert r["trace_texel_over_embree"] == pytest.approx(
            r["trace_texel_rays_per_second"] / r["embree_rays_per_second"])
    assert (out / "trace_against_embree.csv").stat().st_size > 100
    assert any("against Embree on the same rays" in line for line in data["findings"]["speed"])
    assert any("the paper's lookup" in line for line in data["findings"]["speed"])


def test_distance_walk_peers_and_stability_are_measured(tiny_report):
    out, data, _ = tiny_report
    distances = data["distance"]
    assert {r["source"] for r in distances} == {"scan", "mesh"}
    assert min(r["distance_to_nearest_probe"] for r in distances) == 0.0
    assert max(r["distance_to_nearest_probe"] for r in distances) > 0.5
    assert len(data["walk"]) == 4
    # Every probe render measures its guessed surfaces; a mesh-baked probe guesses nothing.
    for r in distances:
        assert 0.0 <= r["guessed_pixels"] <= 1.0 and 0.0 <= r["guessed_error_share"] <= 1.0
        if r["source"] == "mesh":
            assert r["guessed_pixels"] == 0.0 and r["psnr_off_guesses"] == pytest.approx(r["psnr"])
            # Nothing guessed: every pixel is the probe at the eye's.
            assert r["psnr_seen_exact"] == pytest.approx(r["psnr_probe_at_eye"])
    methods = {r["method"].split(" (")[0] for r in data["peers"]["rows"]}
    assert methods == {"probes", "splats", "Poisson mesh"}, data["peers"]["poisson"]
    poisson = data["peers"]["poisson"]
    assert poisson["triangles"] > 100 and poisson["reconstruction_seconds"] > 0
    cases = {c["case"]: c for c in data["stability"]}
    assert set(cases) == {"threads", "coarse levels", "eye approaching a probe", "large world offset",
                          "axis planes", "eye outside the grid", "panorama at a probe"}
    for case in cases.values():
        assert case["criterion"] and isinstance(case["passed"], bool)
    assert cases["threads"]["passed"] and cases["coarse levels"]["passed"]
    assert cases["large world offset"]["world_offset"][0] > 500000
    images = set(os.listdir(out / "images"))
    for view in data["scene"]["views"]:
        for kind in ("probes", "mesh_probes", "splats", "poisson"):
            assert f"triplet_{kind}_{view['name']}.png" in images
        assert f"confusion_{view['name']}.png" in images


def test_planning_section_compares_auto_adaptive_and_bytes_per_probe(tiny_report):
    from lfprobe.core.probe_set import PAPER_BYTES_PER_2048_PROBE

    out, data, result = tiny_report
    plan = data["planning"]
    # a. auto against every fixed resolution of the preset (64², 128²), with the verdict's figures
    rows = plan["resolution"]["rows"]
    fixed = [r for r in rows if r["setting"].startswith("fixed")]
    assert [(r["resolution"], r["storage"]) for r in fixed] == [
        (64, "full"), (128, "full"), (64, "compact"), (128, "compact")]
    unclassified, auto_full, auto = rows[-3:]
    # the plan's resolutions without classification: every probe kept where the grid put it
    assert unclassified["setting"].startswith("auto resolution only") and unclassified["probes"] == 12
    assert plan["resolution"]["unclassified_psnr"] == unclassified["psnr"]
    # bake --auto records compact storage; the same probes at full precision come with it
    assert auto["setting"].startswith("auto") and auto["probes"] == 12 and auto["storage"] == "compact"
    assert auto_full["storage"] == "full" and auto_full["resolutions"] == auto["resolutions"]
    assert auto["memory_bytes"] < 0.5 * auto_full["memory_bytes"]
    for row in rows:
        assert 0 < row["psnr"] < 100 and 0 <= row["flip"] <= 1 and 0 <= row["hole_rate"] <= 1
        assert row["memory_bytes"] > 0 and row["bake_seconds"] > 0
    assert all(64 <= n <= 4096 for n in auto["resolutions"])
    r = plan["resolution"]
    assert r["best_fixed"] == max(fixed, key=lambda x: x["psnr"])["setting"]
    assert r["psnr_difference_db"] == pytest.approx(auto["psnr"] - r["best_fixed_psnr"])
    assert r["memory_ratio"] == pytest.approx(auto["memory_bytes"] / r["best_fixed_memory_bytes"])
    assert r["matches_best_error"] == (r["psnr_difference_db"] >= -0.1)
    # storage: the same sets loaded full and compact, 7 against 18 bytes a texel on the maps and
    # 16-bit against float32 coarse levels
    from lfprobe.core.probe_set import coarse_level_bytes
    storage = plan["storage"]
    assert [s["resolution"] for s in storage] == [64, 128]
    for s in storage:
        n = s["resolution"]
        assert s["full_memory_bytes_per_probe"] - s["compact_memory_bytes_per_probe"] == \
            11 * n * n + coarse_level_bytes(n) // 2
        assert abs(s["psnr_difference_db"]) < 0.5
    assert os.path.exists(out / "planning_storage.csv")
    # b. adaptive placement against a uniform grid, per walk frame
    placement = plan["placement"]
    adaptive, uniform = placement["adaptive"], placement["uniform"]
    iterations = adaptive["iterations"]
    assert iterations[0]["probes"] == 2 and adaptive["probes"] == 2 + adaptive["added"]
    assert iterations[-1]["mean_unknown_rate"] <= iterations[0]["mean_unknown_rate"]
    assert adaptive["memory_bytes"] <= placement["budget_bytes"]
    assert abs(uniform["probes"] - adaptive["probes"]) <= 1
    frames = plan["placement_frames"]
    walk = len(data["walk"])
    for method in ("adaptive", "uniform grid"):
        rows = [f for f in frames if f["method"] == method]
        # the walk's frames, and the ones halfway between them that placement never saw
        assert sum(f["placed_for"] for f in rows) == walk and len(rows) == 2 * walk - 1
    for key in ("hole_rate", "psnr", "flip"):
        assert adaptive[key] is not None and uniform[key] is not None
        assert adaptive["between_frames"][key] is not None and uniform["between_frames"][key] is not None
    assert placement["scene_grid"]["probes"] == 12 and placement["scene_grid"]["memory_bytes"] == placement["budget_bytes"]
    assert placement["scene_grid"]["hole_rate"] == pytest.approx(sum(w["hole_rate"] for w in data["walk"]) / walk)
    placed = [f for f in frames if f["method"] == "adaptive" and f["placed_for"]]
    assert adaptive["hole_rate"] == pytest.approx(sum(f["hole_rate"] for f in placed) / walk)
    # c. bytes per probe at equal error, against the paper's 24.375 MB
    eq = plan["bytes_at_equal_error"]
    assert eq["psnr"] >= eq["reference_psnr"] - eq["margin_db"] and eq["margin_db"] == 0.1
    assert eq["bytes_per_probe"] <= eq["reference_bytes_per_probe"]
    assert eq["fraction_of_paper"] == pytest.approx(eq["bytes_per_probe"] / PAPER_BYTES_PER_2048_PROBE)
    for sentence in data["findings"]["planning"]:
        assert sentence in result.stdout
    assert f"{r['auto_psnr']:.2f} dB" in data["findings"]["planning"][0]
    images = set(os.listdir(out / "images"))
    assert {"planning_walk_holes.png", "planning_walk_psnr.png"} <= images


def test_a_preset_without_the_planning_section_says_so_on_the_page(tiny_report):
    """The demo preset skips "Model only what a scene needs" (minutes at the paper's density):
    the page keeps the section with a note naming the preset that runs it, and lists no
    planning files."""
    from lfprobe.core.report.page import render_page
    from lfprobe.core.report.presets import get_preset

    assert not get_preset("demo").planning and get_preset("full").planning and get_preset("tiny").planning
    _, data, _ = tiny_report
    page = render_page(dict(data, planning=None, preset="demo"), {})
    section = page[page.index('id="planning"'):]
    assert "Not run by the preset &#x27;demo&#x27;" in section and "--preset full" in section
    assert "planning_walk.csv" not in page


def test_a_run_without_the_planning_section_leaves_no_planning_file_of_an_earlier_run(tiny_report, tmp_path):
    from lfprobe.core.report.runner import PLANNING_TABLES, _write_tables

    _, data, _ = tiny_report
    for name in PLANNING_TABLES:
        (tmp_path / name).write_text("from an earlier run\n")
    _write_tables(str(tmp_path), dict(data, planning=None))
    written = set(os.listdir(tmp_path))
    assert not written & set(PLANNING_TABLES)
    assert {"sweep.csv", "peers.csv", "distance.csv"} <= written


def test_a_run_deletes_the_report_images_an_earlier_run_left_and_keeps_other_files(tmp_path):
    """A triplet of a setting the preset no longer renders (the demo's mesh-baked grid moved to
    1024², so no mesh triplet) must not stay beside this run's images; a user's own file stays."""
    from lfprobe.core.report.runner import remove_stale_images

    for name in ("triplet_mesh_probes_at_probe.png", "triplet_probes_at_probe.png",
                 "planning_walk_psnr.png", "speed_ms_psnr.png", "my_notes.png", "triplet_probes.txt"):
        (tmp_path / name).write_bytes(b"x")
    removed = remove_stale_images(str(tmp_path), {"triplet_probes_at_probe.png", "speed_ms_psnr.png"})
    assert removed == ["planning_walk_psnr.png", "triplet_mesh_probes_at_probe.png"]
    assert sorted(os.listdir(tmp_path)) == ["my_notes.png", "speed_ms_psnr.png", "triplet_probes.txt",
                                            "triplet_probes_at_probe.png"]


def test_findings_quote_the_measured_figures(tiny_report):
    _, data, result = tiny_report
    first = sorted((r for r in data["at_probe"]
                    if r["view"] == data["at_probe"][0]["view"] and r["filter"] == "bilinear"),
                   key=lambda r: r["resolution"])
    sentence = data["findings"]["at_probe"][0]
    assert f"{first[0]['psnr']:.2f} dB" in sentence
    assert f"{first[-1]['psnr']:.2f} dB" in sentence
    assert f"{first[-1]['psnr_vs_converged_gt']:.2f} dB" in sentence
    assert sentence in result.stdout


def test_mesh_probe_rows_measure_every_filter_and_the_error_at_silhouettes(tiny_report):
    _, data, _ = tiny_report
    filters = {r["filter"] for r in data["at_probe"]}
    assert filters == {"nearest", "bilinear", "bicubic"}
    for r in data["at_probe"]:
        assert 0.0 < r["silhouette_pixels"] < 1.0
        assert 0.0 <= r["silhouette_error_share"] <= 1.0
        assert 0.0 <= r["gt_silhouette_error_share"] <= 1.0
    assert "at silhouettes" in data["findings"]["at_probe"][0]


def test_silhouette_pixels_are_those_beside_a_depth_step_and_carry_their_share_of_the_error():
    import numpy as np

    from lfprobe.core.report.measure import error_share, silhouette_pixels

    depth = np.ones((4, 6), np.float32)
    depth[:, 4:] = 2.0  # a step between columns 3 and 4
    depth[0, 0] = np.inf  # no hit: a step too
    image = {"depth": depth, "width": 6, "height": 4}
    mask = silhouette_pixels(image)
    expected = np.zeros((4, 6), bool)
    expected[:, 3:5] = True
    expected[0, 0] = expected[0, 1] = expected[1, 0] = True
    assert (mask == expected).all()
    status = np.full((4, 6), metrics.STATUS_HIT, np.uint8)
    reference = {"rgba": np.zeros((4, 6, 4), np.float32), "status": status}
    test = {"rgba": np.zeros((4, 6, 4), np.float32), "status": status}
    test["rgba"][0, 3, :3] = 0.5  # an error at a silhouette pixel
    test["rgba"][2, 1, :3] = 0.5  # and the same error away from one
    assert error_share(reference, test, mask) == pytest.approx(0.5)


def test_guessed_figures_are_the_share_of_pixels_on_guesses_their_error_and_the_psnr_without_them():
    import numpy as np

    from lfprobe.core.report.measure import guessed_figures

    status = np.full((4, 6), metrics.STATUS_HIT, np.uint8)
    reference = {"rgba": np.zeros((4, 6, 4), np.float32), "status": status, "width": 6, "height": 4}
    test = {"rgba": np.zeros((4, 6, 4), np.float32), "status": status, "width": 6, "height": 4,
            "guessed": np.zeros((4, 6), np.uint8)}
    test["guessed"][1, 2:5] = 1  # three guessed pixels
    test["rgba"][1, 2, :3] = 0.5  # an error on a guess
    test["rgba"][3, 0, :3] = 0.5  # and the same error elsewhere
    figures = guessed_figures(reference, test)
    assert figures["guessed_pixels"] == pytest.approx(3 / 24)
    assert figures["guessed_error_share"] == pytest.approx(0.5)
    assert figures["psnr_off_guesses"] == pytest.approx(metrics.psnr_over(
        reference["rgba"][..., :3], test["rgba"][..., :3], test["guessed"] == 0))
    # Images without the channel (splats, meshes, older files) have no such figures.
    del test["guessed"]
    assert guessed_figures(reference, test) == {}


def test_psnr_seen_as_exact_keeps_the_guesses_and_takes_every_other_pixel_from_the_stand_in():
    import numpy as np

    status = np.full((4, 6), metrics.STATUS_HIT, np.uint8)
    reference = {"rgba": np.zeros((4, 6, 4), np.float32), "status": status, "width": 6, "height": 4}
    test = {"rgba": np.zeros((4, 6, 4), np.float32), "status": status, "width": 6, "height": 4,
            "guessed": np.zeros((4, 6), np.uint8)}
    stand_in = {"rgba": np.zeros((4, 6, 4), np.float32), "status": status, "width": 6, "height": 4}
    test["guessed"][1, 2:5] = 1
    test["rgba"][1, 2, :3] = 0.5  # an error on a guess: kept
    test["rgba"][3, 0, :3] = 0.5  # an error off the guesses: replaced by the stand-in's pixel
    only_the_guess = dict(test, rgba=test["rgba"].copy())
    only_the_guess["rgba"][3, 0, :3] = 0.0
    expected = metrics.psnr(reference["rgba"][..., :3], only_the_guess["rgba"][..., :3])
    assert metrics.psnr_seen_as(reference, test, stand_in) == pytest.approx(expected)
    stand_in["rgba"][0, 0, :3] = 0.25  # the stand-in's own error off the guesses counts
    assert metrics.psnr_seen_as(reference, test, stand_in) < expected
    del test["guessed"]
    assert metrics.psnr_seen_as(reference, test, stand_in) is None


def test_mesh_probe_from_its_own_centre_reproduces_ground_truth_up_to_its_resolution(native, scene_path, tmp_path):
    """Eye at a mesh-baked probe's centre, 160×120 view (0.46° pixels), against the pixel-centre
    ground truth: PSNR grows by at least 2 dB per doubling of the map and reaches 35 dB at 1024²
    (0.2° texels); measured 29.6 / 34.4 / 37.8 dB at 256 / 512 / 1024 on the development machine."""
    from lfprobe.core.report.scene import load_scene

    scene = load_scene(scene_path)
    view = scene.views[0]
    eye = view.position  # the view's eye is a grid probe of the scene
    assert eye in scene.probe_positions()
    camera = json.dumps(view.camera())
    native.start_ground_truth(scene.mesh, camera, str(tmp_path / "gt.exr"), spp=1).run()
    gt = native.read_image(str(tmp_path / "gt.exr"))
    values = []
    for res in (256, 512, 1024):
        folder = str(tmp_path / f"probe_{res}")
        native.start_bake_probe_set_from_mesh(scene.mesh, folder, resolution=res, positions=[eye]).run()
        image, stats = native.ProbeField.load(folder).render(camera, threads=2)
        assert stats["mean_steps"] == 1.0  # one texel lookup per ray at the probe
        values.append(metrics.psnr(gt["rgba"][..., :3], metrics.visible_colour(image)))
        shutil.rmtree(folder)
    print(f"mesh-baked probe at its own centre, PSNR at 256/512/1024: {', '.join(f'{v:.2f}' for v in values)} dB")
    assert all(b - a >= 2.0 for a, b in zip(values, values[1:])), values
    assert values[-1] >= 35.0, values


def _write_scene(tmp_path, scene_path, **changes):
    with open(scene_path, encoding="utf-8") as stream:
        scene = json.load(stream)
    for key, value in changes.items():
        if value is None:
            scene.pop(key)
        else:
            scene[key] = value
    scene["mesh"] = os.path.join(os.path.dirname(scene_path), scene["mesh"])
    path = tmp_path / "bad.scene.json"
    path.write_text(json.dumps(scene), encoding="utf-8")
    return str(path)


@pytest.mark.parametrize("changes, words", [
    ({"grid": None}, ["grid", "missing"]),
    ({"grid": {"min": [0, 0, 0], "max": [1, 1, 1], "counts": [2, 0, 2]}}, ["grid.counts", "at least 1"]),
    ({"scanners": [[1, 2]]}, ["scanners[0]", "[x, y, z]"]),
    ({"views": [{"name": "a b", "position": [1, 1, 1], "look_at": [2, 2, 2]}]}, ["views[0].name", "file names"]),
    ({"mesh": "/nonexistent/room.obj"}, ["mesh", "no such file"]),
    ({"scan": {"step_deg": -1}}, ["scan.step_deg", "positive"]),
])
def test_scene_errors_name_the_file_and_key(scene_path, tmp_path, changes, words):
    bad = _write_scene(tmp_path, scene_path, **changes)
    result = run_cli("report", "--scene", bad, "--out", tmp_path / "out", "--preset", "tiny")
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    assert bad in result.stderr
    for word in words:
        assert word in result.stderr, (word, result.stderr)


def test_missing_and_malformed_scene_files(tmp_path):
    result = run_cli("report", "--scene", tmp_path / "none.scene.json", "--out", tmp_path / "out")
    assert result.returncode == 2 and "no such scene file" in result.stderr
    broken = tmp_path / "broken.scene.json"
    broken.write_text("{ not json", encoding="utf-8")
    result = run_cli("report", "--scene", broken, "--out", tmp_path / "out")
    assert result.returncode == 2 and "not valid JSON" in result.stderr and str(broken) in result.stderr


def test_pareto_front():
    from lfprobe.core.report.sweep import pareto_front

    rows = [{"ms": 1.0, "q": 20.0}, {"ms": 2.0, "q": 25.0}, {"ms": 3.0, "q": 24.0}, {"ms": 2.0, "q": 22.0},
            {"ms": 4.0, "q": 30.0}, {"ms": 1.0, "q": 20.0 - 1e-9}]
    assert pareto_front(rows, "ms", "q") == [0, 1, 4]
    assert pareto_front(rows, "ms", "q", higher_is_better=False) == [5]


def test_coarser_scans_are_baked_at_the_presets_coarse_scan_resolution_alone():
    """The demo preset bakes its 1° scans at 1024² only (at 2048² the bake is every texel's work
    for few points); a preset without coarse_scan_resolution bakes every density at every fine
    resolution; the densest scan always gets every resolution and the reference's trace settings."""
    import dataclasses

    from lfprobe.core.report.presets import DEFAULT_TRACE, get_preset
    from lfprobe.core.report.sweep import Density, planned_setups

    densities = [Density(0.1, 21_600_004, 0.0, None), Density(1.0, 216_004, 0.0, None)]
    grid = ([0.0, 0.0, 0.0], [1.0, 2.0, 1.0], [3, 5, 2])

    def scan_sets(preset):
        setups = planned_setups(preset, densities, grid, lambda factor: grid)
        return [(s.density.step_deg, s.resolution, len(traces)) for s, traces in setups if s.source == "scan"]

    demo = get_preset("demo")
    # the reference (0.1°, 2048²): the default, the paper's trace and compact storage
    assert scan_sets(demo) == [(0.1, 1024, 1), (0.1, 2048, 3), (1.0, 1024, 1)]
    every = dataclasses.replace(demo, coarse_scan_resolution=None)
    assert scan_sets(every) == [(0.1, 1024, 1), (0.1, 2048, 3), (1.0, 1024, 1), (1.0, 2048, 1)]
    mesh = [s for s, _ in planned_setups(demo, densities, grid, lambda factor: grid) if s.source == "mesh"]
    assert [s.resolution for s in mesh] == [1024]
    reference = planned_setups(demo, densities, grid, lambda factor: grid)[1][1]
    assert reference[0] == DEFAULT_TRACE and len(demo.trace_variants) == 2
