"""Smoke tests of eval and convert end to end: small sizes, real outputs checked against what
they must equal (simulate's are in test_simulate.py, convert's refusals in tests/hostile)."""
import csv
import json
import struct
from pathlib import Path

import numpy as np
import pytest

import fuzzcore
from monitor.cli import main
from monitor.config import load_config

# a tiny synthetic benchmark: two nominal scenes of two frames, one of them held out
SMALL = ["--scenes", "2", "--test-scenes", "1", "--frames", "2", "--prior-scenes", "1",
         "--conditions", "nominal"]


def _png_size(path):
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


def test_eval_writes_the_tables_and_its_rmse_is_the_features_rmse(tmp_path, capsys):
    out = tmp_path / "eval"
    # seed 4: the held-out scene's two frames are a hazard frame in view and a hazard-free one
    assert main(["eval", "-o", str(out), *SMALL, "--seed", "4"]) == 0
    printed = capsys.readouterr().out
    assert "synthetic" in printed and "Table I" in printed and "Table III" in printed
    report = (out / "report.md").read_text()
    for title in ("Table I", "Table II", "Table III", "held-out test scenes"):
        assert title in report
    tables = json.loads((out / "tables.json").read_text())
    assert "synthetic" in tables["note"]
    assert [(r["alpha"], r["beta"]) for r in tables["correlation"]] == [(0.5, 0.1), (0.3, 0.2)]
    assert all(r["frames"] <= 4 for r in tables["correlation"])  # 2 scenes of 2 frames
    recall = tables["recall"]
    assert [(r["condition"], r["setting"]) for r in recall] == [("nominal", "(0.5, 0.1)"),
                                                                ("nominal", "(0.3, 0.2)")]
    assert recall[0]["gts"] == recall[1]["gts"] > 0  # 4 frames of a street have ground truth
    (analysis,) = tables["analysis"]
    assert analysis["gts"] == analysis["tps"] + analysis["fns"] == recall[1]["gts"]
    assert analysis["approved_tps"] <= analysis["tps"] and analysis["identified_fns"] <= analysis["fns"]
    shipped = sorted(p.name for p in Path("rules").glob("*.yaml"))
    assert sorted(r["rules"] for r in tables["rmse"]) == shipped

    # the per-frame table: every frame of both scenes; the held-out ones give the headline again
    frames = [json.loads(line) for line in (out / "frames.jsonl").read_text().splitlines()]
    assert [(f["split"], f["frame"]) for f in frames] == [("train", 0), ("train", 1), ("test", 0), ("test", 1)]
    test = [f for f in frames if f["split"] == "test"]
    hazard = np.array([f["hazard"] for f in test])
    in_view = np.array([f["hazard_in_view"] for f in test])  # the depth view found what P missed
    assert not (in_view & ~hazard).any()
    for name in shipped:
        row = next(r for r in tables["quality"] if r["condition"] == "all" and r["predictor"] == name)
        risk = np.array([f["risk"][name] for f in test])
        assert row["hazards"] == hazard.sum() > 0  # this street's frames hold missed objects
        assert row["hit_rate"] == np.mean(risk[hazard] > load_config().shield.threshold)
        assert row["hit_in_view"] == pytest.approx(np.mean(risk[in_view] > load_config().shield.threshold)
                                                   if in_view.any() else np.nan, nan_ok=True)
        # false alarms at an 80 % hit rate: alarm at the risk of the hazard frame that reaches it
        reach = np.sort(risk[hazard])[::-1][int(np.ceil(0.8 * hazard.sum())) - 1]
        assert row["fpr80"] == np.mean(risk[~hazard] >= reach)
        # the AUROC in view: each pair of a hazard frame in view and a hazard-free frame
        pairs = [(p > n) + 0.5 * (p == n) for p in risk[in_view] for n in risk[~hazard]]
        assert len(pairs) > 0 and row["auroc_in_view"] == pytest.approx(np.mean(pairs), rel=1e-12)
        scored = [(f["risk"][name], f["target"]) for f in test if f["target"] is not None]
        err = np.array([r - t for r, t in scored])
        assert len(scored) > 0 and row["rmse"] == pytest.approx(float(np.sqrt(np.mean(err ** 2))), rel=1e-12)
    depth = next(r for r in tables["depth_view"] if r["condition"] == "all")
    assert depth["hazards_in_view"] == pytest.approx(in_view[hazard].mean(), rel=1e-12)
    # one held-out scene: every resample of the bootstrap is that scene, so each interval is the
    # measure itself, and each paired difference the difference of the measures
    assert "How sure: 95 % intervals" in report and "Against the monitor's rule base fuzzrisk.yaml" in report
    quality = {(r["condition"], r["predictor"]): r for r in tables["quality"]}
    assert {(r["condition"], r["predictor"]) for r in tables["intervals"]} == \
        {(c, name) for c in ("nominal", "all") for name in shipped}
    for row in tables["intervals"]:
        for m in ("pearson", "skill", "hit_rate", "fpr80"):
            value = pytest.approx(quality[(row["condition"], row["predictor"])][m], rel=1e-12, nan_ok=True)
            assert row[f"{m}_lo"] == value and row[f"{m}_hi"] == value  # r: NaN, 2 frames
    for row in tables["paired"]:
        mine, theirs = quality[(row["condition"], row["predictor"])], quality[(row["condition"], "fuzzrisk.yaml")]
        assert row["rmse_diff"] == row["rmse_diff_lo"] == row["rmse_diff_hi"]
        assert row["rmse_diff"] == pytest.approx(mine["rmse"] - theirs["rmse"], rel=1e-12)

    fis = fuzzcore.load("rules/fuzzrisk.yaml")
    for f in frames:
        if f["status"] == "ok":
            assert f["risk"]["fuzzrisk.yaml"] == fis.infer(f["iou"], f["rdd"])
        assert f["unseen"] is None or f["unseen"] <= f["objects"]

    # the same RMSE another way: the held-out scene's feature table through the rule base
    features = tmp_path / "test.csv"
    assert main(["features", "-o", str(features), "--split", "test", *SMALL, "--seed", "4"]) == 0
    with open(features) as f:
        rows = [r for r in csv.DictReader(f) if r["target"] != ""]
    fis = fuzzcore.load("rules/fuzzrisk.yaml")
    err = np.array([fis.infer(float(r["iou"]), float(r["rdd"])) - float(r["target"]) for r in rows])
    row = next(r for r in tables["rmse"] if r["rules"] == "fuzzrisk.yaml")
    assert row["frames"] == len(rows)
    if rows:
        assert row["rmse"] == pytest.approx(float(np.sqrt(np.mean(err ** 2))), rel=1e-12)
        assert row["mae"] == pytest.approx(float(np.mean(np.abs(err))), rel=1e-12)


def test_eval_without_a_bootstrap_has_no_intervals(tmp_path, capsys):
    out = tmp_path / "eval"
    assert main(["eval", "-o", str(out), "--bootstrap", "0", *SMALL]) == 0
    tables = json.loads((out / "tables.json").read_text())
    assert tables["intervals"] == [] and tables["paired"] == []
    assert "How sure" not in (out / "report.md").read_text()
    assert main(["eval", "-o", str(tmp_path / "e2"), "--bootstrap", "-1", *SMALL]) == 2
    assert "--bootstrap -1: must be >= 0 (0: no intervals)" in capsys.readouterr().err


def test_eval_of_a_depth_ablation_says_so(tmp_path, capsys):
    out = tmp_path / "eval"
    assert main(["eval", "-o", str(out), "--bootstrap", "0", "--no-depth-error", "scale", "all", *SMALL]) == 0
    note = ("An ablation: the depth network's fade, grain, blobs, blur, scale switched off "
            "(`monitor.synthetic.without_depth_errors`)")
    assert note in (out / "report.md").read_text()
    assert note in json.loads((out / "tables.json").read_text())["note"]
    assert main(["eval", "-o", str(tmp_path / "e2"), "--no-depth-error", "blobs", "--scene-dir", str(tmp_path),
                 "--prior", str(tmp_path / "prior.npy")]) == 2
    assert "--no-depth-error switches off errors of the synthetic depth network, not of --scene-dir" in \
        capsys.readouterr().err


def test_eval_refuses_an_empty_rules_folder(tmp_path, capsys):
    assert main(["eval", "-o", str(tmp_path / "e"), "--rules-dir", str(tmp_path), *SMALL]) == 2
    assert f"no rule bases (.yaml, .fis) in {tmp_path}" in capsys.readouterr().err


def test_convert_round_trip_keeps_every_output(tmp_path, capsys):
    fis_path, back = tmp_path / "fuzzrisk.fis", tmp_path / "back.yaml"
    assert main(["convert", "rules/fuzzrisk.yaml", str(fis_path)]) == 0
    assert main(["convert", str(fis_path), str(back)]) == 0
    printed = capsys.readouterr().out
    assert f"{fis_path} -> {back}: mamdani system 'fuzzrisk', 2 input(s), 1 output(s), 9 rule(s)" in printed
    assert "[System]" in fis_path.read_text()
    original, converted = fuzzcore.load("rules/fuzzrisk.yaml"), fuzzcore.load(back)
    X = np.stack(np.meshgrid(np.linspace(0, 1, 21), np.linspace(-1, 1, 21)), -1).reshape(-1, 2)
    np.testing.assert_array_equal(converted.evaluate(X), original.evaluate(X))


def test_convert_warns_about_renamed_names(tmp_path, capsys):
    source = tmp_path / "a.fis"
    assert main(["convert", "rules/fuzzrisk.yaml", str(source)]) == 0
    spaced = tmp_path / "b.fis"
    spaced.write_text(source.read_text().replace("Name='iou'", "Name='io u'"))
    assert main(["convert", str(spaced), str(tmp_path / "b.yaml")]) == 0
    err = capsys.readouterr().err
    assert "warning:" in err and "'io u'" in err and "renamed 'io_u'" in err
    assert list(fuzzcore.load(tmp_path / "b.yaml").input_names) == ["io_u", "rdd"]
