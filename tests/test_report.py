"""Reports: tables computed from run logs (real smoke run and synthetic logs with known numbers),
and the HTML checked in a real browser (headless Chromium; skipped where Chromium is absent)."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from suctionbench.cli import app
from suctionbench.evaluation.report import build_report, expand_run_dirs, success_attempt_curve
from suctionbench.runlog.writer import EpisodeLog

CHROMIUM = next((shutil.which(n) for n in ("chromium", "chromium-browser", "google-chrome") if shutil.which(n)), None)
CHROMIUM_FLAGS = [  # headless on a closed network: no background connections, a throwaway profile
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync", "--hide-scrollbars",
]


@pytest.fixture(scope="module")
def smoke_report(tmp_path_factory):
    """A real smoke run of the centroid policy and its report."""
    root = tmp_path_factory.mktemp("smoke")
    result = CliRunner().invoke(app, ["eval", "--policy", "centroid", "--task", "smoke", "--workers", "1",
                                      "--out", str(root / "run"), "--json"])
    assert result.exit_code == 0, result.output
    return build_report([root / "run"], root / "report"), root / "report"


def test_report_from_a_smoke_run(smoke_report):
    report, out = smoke_report
    row = report["rows"][0]
    assert row["policy"] == "centroid" and row["paper success (AP) %"] == "92 (89)"
    assert row["success - paper (points)"] == f"{row['success %'] - 92:+.0f}"
    page = (out / "index.html").read_text()
    images = re.findall(r'<img src="([^"]+)"', page)
    assert images and all((out / name).is_file() for name in ["report.md", *images])
    # two tables (policies x sets, timing), each a header row and one run row
    assert page.count("<table>") == 2 and page.count("<tr>") == 4 and "centroid" in page
    # success among the attempted grasps as the attempt rate grows (sorted by q, best first)
    attempt, rate = success_attempt_curve(np.array([0.9, 0.1, 0.5]), np.array([True, False, False]))
    np.testing.assert_allclose(attempt, [1 / 3, 2 / 3, 1.0])
    np.testing.assert_allclose(rate, [1.0, 0.5, 1 / 3])


def _synthetic_run(path: Path, policy: str, metric: str, results: list[dict], seed: int = 0,
                   task_name: str = "known_objects") -> Path:
    """A run directory as `eval` writes it, with only result records in its logs."""
    (path / "trials").mkdir(parents=True)
    task = {"name": task_name, "set": "adversarial", "trials": len(results), "placement": "stable",
            "seed": seed, "stable_poses": 3, "metrics": ["pc3d", "ss", "wr", "rwr"], "description": ""}
    (path / "run.json").write_text(json.dumps({"task": task, "policy": policy, "model": None, "metric": metric,
                                               "cup": "default", "trials": len(results), "seed": seed}))
    for i, result in enumerate(results):
        record = {"object": f"adversarial/obj{i % 3}", "valid": True, "failure": None if result["success"] else
                  "no_seal", "label_rwr": 0.0, "sim_time": 4.0, "plan_time": 0.5, "sensing_time": 0.0, **result}
        with EpisodeLog(path / "trials" / f"trial_{i:05d}.mcap", {"policy": policy}) as log:
            log.log_result(1.0, record)
    return path


def test_known_objects_tables_from_logs(tmp_path):
    # Top-ranked grasps: q ranks the two successes first -> AP 1, success 2/4.
    known = _synthetic_run(tmp_path / "analytic" / "rwr", "analytic", "rwr", [
        {"success": s, "policy_q": q} for s, q in ((True, 0.9), (False, 0.2), (True, 0.8), (False, 0.1))])
    # Random grasps: ss ranks successes first (AP 1, all on the right side of 0.5: accuracy 1,
    # Spearman of ranks (4,3,2,1) with tied success ranks (3.5,3.5,1.5,1.5) = 4 / (2 sqrt 5) =
    # sqrt 0.8); pc3d ranks them last: precision 1/3 at recall 1/2 and 2/4 at recall 1, so step-wise
    # AP = (1/3 + 1/2) / 2 = 5/12, accuracy 0, Spearman -sqrt 0.8.
    grasps = [(True, 0.9, 0.1), (True, 0.8, 0.2), (False, 0.3, 0.7), (False, 0.2, 0.6)]
    random = _synthetic_run(tmp_path / "random", "random-surface", "rwr", [
        {"success": s, "policy_q": None, "label_scores": {"ss": a, "pc3d": b}} for s, a, b in grasps])
    assert expand_run_dirs([tmp_path / "analytic"]) == [known]  # a directory of runs is expanded
    report = build_report([tmp_path / "analytic", random], tmp_path / "report")
    top = report["tables"]["Known objects: top-ranked grasp per 3D metric"]
    assert top == [{"metric": "rwr", "set": "adversarial", "trials": 4, "AP %": 100.0, "success %": 50.0,
                    "paper AP / success %": "100 / 92", "success - paper (points)": "-42"}]
    rows = {r["metric"]: r for r in report["tables"]["Known objects: random-grasp classification"]}
    assert (rows["ss"]["AP %"], rows["ss"]["accuracy %"], rows["ss"]["successes"]) == (100.0, 100.0, 2)
    assert rows["ss"]["Spearman"] == pytest.approx(np.sqrt(0.8), abs=1e-3)  # ranks 1..4 vs 0,0,1,1
    assert (rows["pc3d"]["AP %"], rows["pc3d"]["accuracy %"]) == (41.7, 0.0)
    assert rows["pc3d"]["Spearman"] == pytest.approx(-np.sqrt(0.8), abs=1e-3)
    assert rows["ss"]["paper AP / acc. % / Spearman"] == "75 / 74 / 0.49"
    assert "Known objects: random-grasp classification" in (tmp_path / "report" / "report.md").read_text()


def test_the_image_bound_is_a_known_state_row(tmp_path):
    # analytic-image ranks the image's grasps in the true state: a row of the known-objects table
    # named by its metric and where its grasps came from, not a policy of the novel-objects tables.
    bound = _synthetic_run(tmp_path / "img", "analytic-image", "rwr", [
        {"success": s, "policy_q": q} for s, q in ((True, 0.9), (False, 0.2), (False, 0.8), (True, 0.1))])
    report = build_report([bound], tmp_path / "report")
    (row,) = report["tables"]["Known objects: top-ranked grasp per 3D metric"]
    # q ranks success, failure, failure, success: AP = (1/1 + 2/4) / 2 = 0.75; no paper figure
    assert (row["metric"], row["AP %"], row["success %"]) == ("rwr of the image's grasps", 75.0, 50.0)
    assert row["paper AP / success %"] == "-" and "Novel objects: policies x sets" not in report["tables"]
    timing = report["tables"]["The pick cycle (means per trial)"]
    assert [r["run"] for r in timing] == ["analytic-image-rwr / adversarial"]
    # ranked believing the density uniform: a row of its own, named for the belief
    blind = _synthetic_run(tmp_path / "uniform", "analytic-image-uniform", "rwr", [
        {"success": s, "policy_q": q} for s, q in ((False, 0.9), (True, 0.2))])
    rows = build_report([bound, blind], tmp_path / "report2")["tables"]["Known objects: top-ranked grasp per 3D metric"]
    assert [(r["metric"], r["success %"]) for r in rows] == [
        ("rwr of the image's grasps", 50.0), ("rwr of the image's grasps, uniform density believed", 50.0)]


def test_runs_of_several_seeds_are_pooled(tmp_path):
    # Seed 0: q ranks successes 1st, 2nd and 4th -> step-wise AP (1 + 1 + 3/4) / 3 = 0.9167, 3/4
    # successes; seed 1: the one success ranked 2nd -> AP 1/2, 1/4. Pooled: 4 of 8 = 50 %, binomial
    # standard error sqrt(0.5 * 0.5 / 8) = 17.7 points, mean AP 70.8 %; each object's trials add up
    # over the seeds (obj0: trials 0 and 3 of each run, 2/2 and 0/2 -> 2/4).
    runs = [_synthetic_run(tmp_path / f"centroid_s{seed}", "centroid", "rwr",
                           [{"success": s, "policy_q": q} for s, q in trials], seed=seed, task_name="adversarial")
            for seed, trials in ((0, ((True, 0.9), (True, 0.8), (False, 0.7), (True, 0.6))),
                                 (1, ((False, 0.9), (True, 0.8), (False, 0.1), (False, 0.2))))]
    report = build_report(runs, tmp_path / "report")
    assert [r["policy"] for r in report["rows"]] == ["centroid [seed 0]", "centroid [seed 1]"]
    assert [r["AP %"] for r in report["rows"]] == [91.7, 50.0]
    assert report["tables"]["Novel objects: pooled over seeds"] == [
        {"policy": "centroid", "set": "adversarial", "seeds": "0, 1", "trials": 8, "success %": 50.0,
         "+- se (points)": 17.7, "per seed": "3/4, 1/4", "mean AP %": 70.8}]
    assert "centroid / adversarial: 2/4" in (tmp_path / "report" / "report.md").read_text()
    # one seed's report has no pooled table and no seed marks
    single = build_report(runs[:1], tmp_path / "single")
    assert "Novel objects: pooled over seeds" not in single["tables"]
    assert single["rows"][0]["policy"] == "centroid"


def test_report_bad_input(tmp_path):
    result = CliRunner().invoke(app, ["report", str(tmp_path / "nope"), "--out", str(tmp_path / "r"), "--json"])
    assert result.exit_code == 2 and "no run.json" in json.loads(result.stdout.strip().splitlines()[-1])["error"]
    assert not (tmp_path / "r").exists()  # nothing half-written


def _chromium(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    profile = cwd / "chromium-profile"
    return subprocess.run([CHROMIUM, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=120, check=False)


@pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed (CI installs it)")
def test_report_renders_in_headless_chromium(smoke_report, tmp_path):
    _, out = smoke_report
    page = (out / "index.html").read_text()
    # 1. In the browser every image has loaded and decoded, and nothing overflows a 1280 px window:
    #    a probe script (added to a copy; the report itself has no scripts) writes what it found
    #    into the DOM, which --dump-dom prints after the load event.
    probe = ("<script>addEventListener('load', () => { const b = document.body;"
             " b.dataset.images = document.images.length;"
             " b.dataset.broken = [...document.images].filter(i => !(i.complete && i.naturalWidth > 0)).length;"
             " b.dataset.overflow = document.documentElement.scrollWidth > innerWidth; });</script>")
    probed = out / "probe.html"
    probed.write_text(page.replace("</body>", probe + "</body>"))
    try:
        dom = _chromium("--window-size=1280,1024", "--virtual-time-budget=10000", "--dump-dom",
                        probed.as_uri(), cwd=tmp_path)
    finally:
        probed.unlink()
    assert dom.returncode == 0, dom.stderr[-2000:]
    found = dict(re.findall(r'data-(images|broken|overflow)="([^"]*)"', dom.stdout))
    expected_images = page.count("<img ")
    assert found == {"images": str(expected_images), "broken": "0", "overflow": "false"}, found
    assert expected_images >= 1  # curves (a success) or the gallery (a failure)
    # 2. The screenshot shows a rendered page: text and table rules (dark pixels) and the figures.
    shot = tmp_path / "report.png"
    run = _chromium("--window-size=1280,2400", f"--screenshot={shot}", (out / "index.html").as_uri(), cwd=tmp_path)
    assert run.returncode == 0 and shot.is_file(), run.stderr[-2000:]
    pixels = np.asarray(Image.open(shot).convert("L"), dtype=float)
    assert pixels.shape == (2400, 1280)
    dark = pixels < 100
    assert 0.002 < dark.mean() < 0.3  # neither blank nor a black page
    assert dark[:300].any(axis=1).sum() > 20  # the heading and the first table at the top


def test_report_opens_with_the_headline_figure_and_ends_with_command_and_versions(smoke_report):
    from suctionbench.evaluation.runner import run_records

    report, out = smoke_report
    page = (out / "index.html").read_text()
    assert report["figures"][0] == "headline.png"
    assert page.index('src="headline.png"') < page.index("<table>")  # the figure comes before the tables
    headline = np.asarray(Image.open(out / "headline.png").convert("RGB"), dtype=int)
    assert (np.abs(headline - (76, 120, 168)).sum(axis=-1) < 30).any()  # a success bar (#4C78A8)
    assert (headline.sum(axis=-1) < 30).any()  # the paper's black markers (centroid: 92 % on basic)
    # every object of the run has a card: its thumbnail beside its successes / trials
    records = [r for r in run_records(out.parent / "run") if r.get("valid")]
    expected = {}
    for r in records:
        s, n = expected.get(r["object"], (0, 0))
        expected[r["object"]] = (s + bool(r["success"]), n + 1)
    cards = re.findall(r'<figure class="object"><img src="(object_[^"]+\.png)"[^>]*><figcaption><b>([^<]+)</b>'
                       r"<br>centroid / [a-z]+: (\d+)/(\d+)</figcaption>", page)
    assert {key: (int(s), int(n)) for _, key, s, n in cards} == expected
    for image, *_ in cards:
        thumb = np.asarray(Image.open(out / image).convert("RGB"))
        assert thumb.shape == (96, 96, 3) and (thumb < 200).any() and (thumb == 255).all(axis=-1).any()
    footer = page[page.index("<footer>"):]
    assert "Versions: suctionbench" in footer and "mujoco 3." in footer and "seed 0" in footer
    assert "Report: <code>" in footer
    assert "FACTS" not in page and "shared/" not in page and "Mahler et al." in page
    markdown = (out / "report.md").read_text()
    assert markdown.index("headline.png") < markdown.index("| policy |") < markdown.index("## Runs and versions")


def test_quality_overlay_colours_and_marks():
    # q 0 is drawn red, q 1 green, unscored pixels grey (depth), and the executed grasp a white cross.
    from suctionbench.evaluation.figures import QUALITY_MARGIN, QUALITY_ZOOM, quality_overlay

    depth = np.full((100, 120), 0.7, dtype=np.float32)
    quality = np.full(depth.shape, np.nan, dtype=np.float32)
    quality[40:60, 50:60], quality[40:60, 60:70] = 0.0, 1.0
    image = quality_overlay(depth, quality, (65.0, 45.0))
    side = (20 + 2 * QUALITY_MARGIN) * QUALITY_ZOOM
    assert image.shape == (side, side, 3) and image.dtype == np.uint8
    at = lambda u, v: image[(v - 40 + QUALITY_MARGIN) * QUALITY_ZOOM, (u - 50 + QUALITY_MARGIN) * QUALITY_ZOOM]  # noqa: E731
    red, green, grey, cross = at(52, 58), at(68, 58), at(45, 50), at(65, 45)
    assert red[0] > 200 and red[1] < 80 and green[1] > 200 and green[0] < 80
    assert grey[0] == grey[1] == grey[2] and tuple(cross) == (255, 255, 255)
    with pytest.raises(ValueError, match="no scored pixel"):
        quality_overlay(depth, np.full(depth.shape, np.nan), None)


def test_report_shows_a_dense_policys_quality_maps(tmp_path):
    # A smoke run of fc-gqcnn logs its quality map; the report draws it in its own gallery.
    result = CliRunner().invoke(app, ["eval", "--policy", "fc-gqcnn", "--task", "smoke", "--workers", "1",
                                      "--out", str(tmp_path / "run"), "--json"])
    assert result.exit_code == 0, result.output
    build_report([tmp_path / "run"], tmp_path / "report")
    page = (tmp_path / "report" / "index.html").read_text()
    names = re.findall(r'<img src="(quality_[^"]+)"', page)
    assert names and "Quality maps" in page and "Quality maps" in (tmp_path / "report" / "report.md").read_text()
    picture = np.asarray(Image.open(tmp_path / "report" / names[0]))
    assert picture.ndim == 3 and (picture == 255).all(axis=2).any()  # in colour, with the grasp's cross


def test_two_tasks_of_one_policy_and_set_keep_their_own_object_counts(tmp_path):
    # The known-state policy runs on the adversarial set twice (its novel-set task and known_objects):
    # one key each in the per-object counts (the second used to overwrite the first's), and two tasks
    # are not two seeds: no seed marks, no pooled row.
    runs = [_synthetic_run(tmp_path / task, "analytic", "rwr", [{"success": s, "policy_q": 0.5} for s in wins],
                           task_name=task)
            for task, wins in (("adversarial", (True, True, False)), ("known_objects", (False, False, False)))]
    report = build_report(runs, tmp_path / "report")
    page = (tmp_path / "report" / "report.md").read_text()
    assert "analytic-rwr / adversarial (adversarial): 1/1" in page  # obj0: trial 0 of each run
    assert "analytic-rwr / adversarial (known_objects): 0/1" in page
    assert "[seed" not in page and "Novel objects: pooled over seeds" not in report["tables"]
