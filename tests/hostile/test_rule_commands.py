"""Hostile command lines for the rule-file commands: ``infer``, ``convert`` and ``tune``.

Documented outcome: exit code 2 with ``fuzzrisk COMMAND: error: ...`` naming the argument or
file, checked before any work, and no file a user owns changed; or the command's result.
"""
import csv
import os
from pathlib import Path

import numpy as np
import pytest

import fuzzcore
from monitor import cli

ROOT = Path(__file__).resolve().parents[2]
RULES = ROOT / "rules" / "fuzzrisk.yaml"


def _run(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


# --------------------------------------------------------------------------- infer (item 8)
def test_infer_refuses_an_input_given_twice(capsys):
    code, out, err = _run(capsys, "infer", RULES, "--iou", "0.4", "--rdd", "0.3", "--iou", "0.9")
    assert code == 2 and out == ""
    assert "--iou is given twice (0.4, then '0.9'); give each input once" in err


def test_infer_refuses_a_value_too_large_for_a_float(capsys):
    code, _, err = _run(capsys, "infer", RULES, "--iou", "1e400", "--rdd", "0.3")
    assert code == 2 and "--iou '1e400' is too large for a float64" in err
    code, out, _ = _run(capsys, "infer", RULES, "--iou", "0.4", "--rdd", "0.3")
    assert code == 0 and out == f"risk = {fuzzcore.load(RULES).infer(0.4, 0.3):.6g}\n"


# --------------------------------------------------------------------------- convert (items 11, 12)
def test_convert_refuses_its_input_under_another_name(tmp_path, capsys):
    source = tmp_path / "mine.yaml"
    fuzzcore.load(RULES).save(source)
    before = source.read_bytes()
    link = tmp_path / "link.yaml"
    os.link(source, link)  # a hard link: the same file, which resolve() does not see
    code, _, err = _run(capsys, "convert", source, link, "--overwrite")
    assert code == 2 and f"{link} is the same file as {source}, which is read" in err
    (tmp_path / "sub").mkdir()
    code, _, err = _run(capsys, "convert", source, tmp_path / "sub" / ".." / "mine.yaml", "--overwrite")
    assert code == 2 and "is the same file as" in err
    assert source.read_bytes() == before


def test_convert_does_not_overwrite_without_being_asked(tmp_path, capsys):
    target = tmp_path / "out.fis"
    target.write_text("mine\n")
    code, _, err = _run(capsys, "convert", RULES, target)
    assert code == 2 and f"{target} already exists; choose another name or allow replacing it (--overwrite)" in err
    assert target.read_text() == "mine\n"
    code, _, _ = _run(capsys, "convert", RULES, target, "--overwrite")
    assert code == 0 and fuzzcore.load(target).rules == fuzzcore.load(RULES).rules


@pytest.mark.parametrize("target, words", [
    ("out.txt", "unknown rule base format '.txt'"),
    ("missing/out.yaml", "the folder"),
    ("folder.yaml", "is a folder"),
])
def test_convert_checks_the_output_path_before_reading(tmp_path, capsys, target, words):
    # the input does not exist either: the output's error comes first
    (tmp_path / "folder.yaml").mkdir()
    code, _, err = _run(capsys, "convert", tmp_path / "nothing.yaml", tmp_path / target)
    assert code == 2 and words in err and "nothing.yaml: no such" not in err


# --------------------------------------------------------------------------- tune (items 10, 12)
def _features(path: Path, n_scenes=4, frames=10, seed=0):
    fis = fuzzcore.load(RULES)
    rng = np.random.default_rng(seed)
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["scene", "iou", "rdd", "target"])
        for s in range(n_scenes):
            for _ in range(frames):
                iou, rdd = rng.uniform(0, 1), rng.uniform(-1, 1)
                target = min(1.0, max(0.0, fis.infer(iou, rdd) + rng.normal(0, 0.05)))
                writer.writerow([f"scene-{s}", f"{iou:.4f}", f"{rdd:.4f}", f"{target:.4f}"])
    return path


def test_tune_refuses_to_write_over_its_starting_rules_before_any_work(tmp_path, capsys):
    mine = tmp_path / "mine.yaml"
    fuzzcore.load(RULES).save(mine)
    before = mine.read_bytes()
    # the features file does not even exist: the output is checked first, so no tuning starts
    code, out, err = _run(capsys, "tune", "--features", tmp_path / "none.csv", "--method", "pso",
                          "--rules", mine, "-o", mine, "--overwrite")
    assert code == 2 and out == ""
    assert f"{mine} is the same file as {mine}, which is read: write to another file" in err
    assert mine.read_bytes() == before


@pytest.mark.parametrize("output, words", [
    ("out.csv", "unknown rule base format '.csv'"),
    ("no/such/folder/out.yaml", "does not exist; create it first"),
])
def test_tune_checks_the_output_before_any_work(tmp_path, capsys, output, words):
    train = _features(tmp_path / "train.csv")
    code, out, err = _run(capsys, "tune", "--features", train, "--method", "pso", "--rules", RULES,
                          "-o", tmp_path / output, "--swarm-size", "5", "--swarm-iter", "1")
    assert code == 2 and out == "" and words in err


def test_tune_does_not_overwrite_without_being_asked(tmp_path, capsys):
    train = _features(tmp_path / "train.csv")
    out = tmp_path / "out.yaml"
    out.write_text("mine\n")
    code, printed, err = _run(capsys, "tune", "--features", train, "--method", "pso", "--rules", RULES, "-o", out,
                              "--swarm-size", "5", "--swarm-iter", "1")
    assert code == 2 and printed == "" and "already exists" in err and "--overwrite" in err
    assert out.read_text() == "mine\n"


def test_tune_records_portable_paths_and_the_data_hash(tmp_path, capsys, monkeypatch):
    import hashlib
    project = tmp_path / "project"
    (project / "data").mkdir(parents=True)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    train = _features(project / "data" / "train.csv")
    test = _features(elsewhere / "test.csv", seed=1)
    monkeypatch.chdir(project)
    code, _, err = _run(capsys, "tune", "--features", train, "--method", "pso", "--rules", RULES,
                        "-o", "tuned.yaml", "--test", test, "--swarm-size", "5", "--swarm-iter", "1", "--seed", "1")
    assert code == 0, err
    tuning = fuzzcore.load(project / "tuned.yaml").metadata["tuning"]
    # inside the project: relative to it; outside and given absolute: the file name only
    assert tuning["data"]["file"] == "data/train.csv"
    assert tuning["data"]["sha256"] == hashlib.sha256(train.read_bytes()).hexdigest()
    assert tuning["test"]["file"] == "test.csv"
    assert tuning["test"]["sha256"] == hashlib.sha256(test.read_bytes()).hexdigest()
    assert tuning["command"].startswith("fuzzrisk tune --features data/train.csv --method pso --rules fuzzrisk.yaml "
                                        "-o tuned.yaml --test test.csv")
    assert str(tmp_path) not in (project / "tuned.yaml").read_text()
