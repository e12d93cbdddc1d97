"""``fuzzrisk tune``: the command end to end on a small feature table."""
import csv

import numpy as np
import pytest

import fuzzcore
from monitor import cli

RULES = "rules/fuzzrisk.yaml"


def _table(path, n_scenes, seed, holes=False):
    """A feature CSV in the format of ``fuzzrisk features``; with ``holes``, rows without target/features."""
    rng = np.random.default_rng(seed)
    with open(path, "w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(["scene", "frame", "condition", "iou", "rdd", "target"])
        for s in range(n_scenes):
            for frame in range(15):
                iou, rdd = rng.beta(2, 2), float(np.clip(rng.normal(0.1, 0.4), -1, 1))
                target = float(np.clip(0.6 * max(rdd, 0) + 0.3 * (1 - iou) + rng.normal(0, 0.05), 0, 1))
                row = [f"scene-{seed}-{s}", frame, "nominal", repr(iou), repr(rdd), repr(target)]
                if holes and frame == 0:
                    row[5] = ""
                if holes and frame == 1:
                    row[3] = row[4] = ""
                writer.writerow(row)
    return path


@pytest.fixture(scope="module")
def tables(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tune")
    return _table(folder / "train.csv", 8, 0, holes=True), _table(folder / "test.csv", 3, 1)


@pytest.mark.parametrize("method, extra", [
    ("patternsearch", ["--folds", "2", "--max-iter", "10", "--variables", "rdd"]),
    ("pso", ["--swarm-size", "10", "--swarm-iter", "4", "--allow-off"]),
    ("joint", ["--folds", "1", "--max-iter", "10", "--swarm-size", "10", "--swarm-iter", "3"]),
])
def test_tune_command_writes_a_tuned_system_with_its_provenance(tables, tmp_path, capsys, method, extra):
    train, test = tables
    out = tmp_path / f"{method}.yaml"
    code = cli.main(["tune", "--features", str(train), "--method", method, "--rules", RULES, "-o", str(out),
                     "--test", str(test), "--seed", "4", *extra])
    assert code == 0
    printed = capsys.readouterr().out
    # 8 scenes x 15 frames, frame 0 without a target and frame 1 without features in each
    assert "104 rows in 8 groups (skipped 8 without a target, 8 without features)" in printed
    tuned = fuzzcore.load(out)
    tuning = tuned.metadata["tuning"]
    assert tuned.name == method and tuning["started_from"] == "fuzzrisk"
    assert tuning["method"] == {"pso": "particleswarm"}.get(method, method)
    assert tuning["seed"] == 4
    assert tuning["data"]["file"] == train.name and len(tuning["data"]["sha256"]) == 64  # outside the cwd: the name
    assert tuning["data"]["skipped_no_target"] == 8 and tuning["data"]["n_samples"] == 104
    assert tuning["command"].startswith(f"fuzzrisk tune --features {train.name} --method {method}")
    # the recorded test score is the tuned system's RMSE on the test table, computed here apart
    rows = list(csv.DictReader(open(test)))
    X = np.array([[float(r["iou"]), float(r["rdd"])] for r in rows])
    y = np.array([float(r["target"]) for r in rows])
    rmse = np.sqrt(np.mean((tuned.evaluate(X)[:, 0] - y) ** 2))
    assert tuning["test"]["final"] == pytest.approx(rmse, rel=1e-12)
    assert f"{rmse:.5f} (tuned)" in printed
    if method != "patternsearch":  # the swarm starts from the given rules; cross-validation may not
        assert tuning["score"]["final"] <= tuning["score"]["initial"]


def test_tune_command_reports_user_errors(tables, tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("scene,iou,target\ns,0.5,0.2\n", encoding="utf-8")
    code = cli.main(["tune", "--features", str(bad), "--method", "pso", "--rules", RULES,
                     "-o", str(tmp_path / "o.yaml")])
    assert code == 2
    err = capsys.readouterr().err
    assert "missing column(s) rdd" in err and str(bad) in err
    train, _ = tables
    code = cli.main(["tune", "--features", str(train), "--method", "patternsearch", "--rules", RULES,
                     "-o", str(tmp_path / "o.yaml"), "--folds", "20"])
    assert code == 2
    assert "n_folds = 20 but the data have only 8 groups" in capsys.readouterr().err


def test_tune_lse_writes_a_monotone_sugeno_system_with_its_provenance(tables, tmp_path, capsys):
    train, test = tables
    out = tmp_path / "lse.yaml"
    code = cli.main(["tune", "--features", str(train), "--method", "lse", "--rules", RULES, "-o", str(out),
                     "--test", str(test), "--monotone", "iou:-", "--grid", "21"])
    assert code == 0
    printed = capsys.readouterr().out
    tuned = fuzzcore.load(out)
    tuning = tuned.metadata["tuning"]
    assert tuned.type == "sugeno" and tuning["method"] == "lse" and tuning["seed"] is None
    assert tuning["settings"]["monotone"] == {"iou": -1} and tuning["settings"]["grid"] == 21
    assert tuning["command"] == (f"fuzzrisk tune --features {train.name} --method lse --rules {RULES} -o {out.name} "
                                 f"--test {test.name} --order 1 --monotone iou:- --grid 21")
    assert f"fuzzrisk check {out} --monotone iou:-:" in printed
    assert "risk decreasing in iou: holds" in printed and "result: PASS" in printed
    rows = list(csv.DictReader(open(test)))
    X = np.array([[float(r["iou"]), float(r["rdd"])] for r in rows])
    y = np.array([float(r["target"]) for r in rows])
    assert tuning["test"]["final"] == pytest.approx(np.sqrt(np.mean((tuned.evaluate(X)[:, 0] - y) ** 2)), rel=1e-12)
    assert tuning["score"]["final"] < tuning["score"]["initial"]


@pytest.mark.parametrize("extra, words", [
    (["--method", "pso", "--monotone", "iou:-"], "--monotone and --unbounded are options of --method lse"),
    (["--method", "lse", "--metric", "mae"], "--metric mae: least squares (--method lse) minimises the RMSE"),
    (["--method", "lse", "--monotone", "iou:-", "iou:+"], "--monotone names 'iou' twice"),
    (["--method", "lse", "--monotone", "iou"], "monotone property 'iou': expected INPUT:+ or INPUT:-"),
])
def test_tune_lse_options_are_checked_before_any_work(tables, tmp_path, capsys, extra, words):
    train, _ = tables
    out = tmp_path / "o.yaml"
    code = cli.main(["tune", "--features", str(train), "--rules", RULES, "-o", str(out), *extra])
    assert code == 2 and words in capsys.readouterr().err and not out.exists()
