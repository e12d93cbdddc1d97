"""YAML rule bases: strict safe reading with errors naming file and place; round trips."""
import numpy as np
import pytest
from hypothesis import given, strategies as st

import fuzzcore
from fuzzcore import RuleBaseError
from fuzzcore.yaml_format import dumps, loads

from strategies import mamdani_systems, sugeno_systems

GOOD = """\
name: demo
inputs:
  iou:
    range: [0, 1]
    terms:
      low: [trimf, 0, 0, 0.5]
      high: [trimf, 0.5, 1, 1]
  rdd:
    range: [-1, 1]
    terms:
      low: [trapmf, -1, -1, -0.5, 0]
      high: [trapmf, 0, 0.5, 1, 1]
outputs:
  risk:
    range: [0, 1]
    terms:
      low: [trimf, 0, 0, 0.5]
      high: [trimf, 0.5, 1, 1]
rules:
  - if rdd is high then risk is high
  - rule: if rdd is low and iou is high then risk is low
    weight: 0.5
"""


def test_good_file_loads_with_defaults():
    fis = loads(GOOD, "good.yaml")
    assert fis.name == "demo" and fis.input_names == ("iou", "rdd")
    assert (fis.and_method, fis.implication, fis.aggregation, fis.defuzzifier, fis.resolution) == (
        "min", "min", "max", "centroid", 101)
    assert fis.rules[0].antecedent == (0, 2) and fis.rules[0].consequent == (2,)
    assert fis.rules[1].antecedent == (2, 1) and fis.rules[1].weight == 0.5


@pytest.mark.parametrize("old, new, place, message", [
    ("name: demo", "name: demo\ncolour: red", "line 2, top level", "unknown key(s) colour"),
    ("    range: [0, 1]\n    terms:\n      low: [trimf, 0, 0, 0.5]",
     "    range: [0, 1]\n    shape: odd\n    terms:\n      low: [trimf, 0, 0, 0.5]", "inputs.iou", "unknown key(s) shape"),
    ("if rdd is high then risk is high", "if rdd is huge then risk is high", "rules[0]",
     "'rdd' has no term 'huge'; its terms are: low, high"),
    ("if rdd is high then risk is high", "if speed is high then risk is high", "rules[0]",
     "unknown variable 'speed'; expected one of: iou, rdd"),
    ("low: [trimf, 0, 0, 0.5]\n      high: [trimf, 0.5, 1, 1]\n  rdd",
     "low: [trimf, 0.5, 0, 0]\n      high: [trimf, 0.5, 1, 1]\n  rdd", "inputs.iou", "non-decreasing"),
    ("[trapmf, -1, -1, -0.5, 0]", "[trapmf, -1, -1, oops, 0]", "inputs.rdd.terms.low", "'oops' is not a finite number"),
    ("[trapmf, -1, -1, -0.5, 0]", "[trapezium, -1, -1, -0.5, 0]", "inputs.rdd.terms.low",
     "unknown membership function 'trapezium'"),
    ("if rdd is high then risk is high", "if rdd is high and iou is low or iou is high then risk is high",
     "rules[0]", "mixes 'and' and 'or'"),
    ("    weight: 0.5", "    weight: 1.5", "rules[1]", "expected a number in [0, 1]"),
    ("name: demo", "name: demo\ndefuzzifier: middle", "defuzzifier", "expected one of centroid"),
])
def test_errors_name_file_place_and_problem(old, new, place, message):
    text = GOOD.replace(old, new, 1)
    assert text != GOOD
    with pytest.raises(RuleBaseError) as err:
        loads(text, "rules/bad.yaml")
    text = str(err.value)
    assert text.startswith("rules/bad.yaml: ") and place in text and message in text


def test_empty_rule_list_is_an_error():
    with pytest.raises(RuleBaseError, match=r"bad.yaml: line \d+, rules: expected a non-empty list of rules"):
        loads(GOOD.split("rules:")[0] + "rules: []\n", "bad.yaml")


def test_duplicate_keys_are_errors_not_silently_dropped():
    text = GOOD.replace("      high: [trimf, 0.5, 1, 1]\n  rdd", "      high: [trimf, 0.5, 1, 1]\n      low: [trimf, 0, 0, 1]\n  rdd")
    with pytest.raises(RuleBaseError, match=r"x.yaml: line 8: duplicate key 'low' \(first at line 6\)"):
        loads(text, "x.yaml")


@pytest.mark.parametrize("tag", ["!!python/object/apply:os.system ['echo pwned']",
                                 "!!python/name:builtins.print"])
def test_object_constructing_tags_are_refused(tag):
    with pytest.raises(RuleBaseError, match="x.yaml: line 1: not valid safe YAML"):
        loads(f"name: {tag}\n" + GOOD.split("\n", 1)[1], "x.yaml")


def test_a_safe_tag_of_the_wrong_type_is_still_an_error():
    with pytest.raises(RuleBaseError, match="x.yaml: line 1, name: name b'hello' must be text"):
        loads("name: !!binary aGVsbG8=\n" + GOOD.split("\n", 1)[1], "x.yaml")


def test_not_a_mapping_and_empty_file():
    with pytest.raises(RuleBaseError, match="expected a mapping"):
        loads("- a\n- b\n", "x.yaml")
    with pytest.raises(RuleBaseError, match="the file is empty"):
        loads("", "x.yaml")


def test_missing_file_and_unknown_extension(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such rule base file"):
        fuzzcore.load(tmp_path / "none.yaml")
    with pytest.raises(ValueError, match=r"unknown rule base format '\.txt'"):
        fuzzcore.load(tmp_path / "rules.txt")


def test_names_that_yaml_would_turn_into_booleans_survive(tmp_path):
    text = GOOD.replace("low: [trimf, 0, 0, 0.5]\n      high", "'no': [trimf, 0, 0, 0.5]\n      high", 1)
    text = text.replace("if rdd is low and iou is high", "if rdd is low and iou is no")
    fis = loads(text, "x.yaml")
    assert fis.inputs[0].terms[0].name == "no"
    assert loads(dumps(fis)) == fis


@given(st.one_of(mamdani_systems(textual=True), sugeno_systems(textual=True)))
def test_save_load_round_trip_is_equal(system):
    again = loads(dumps(system))
    assert again == system
    x = [[0.5 * sum(v.range) for v in system.inputs]]
    np.testing.assert_array_equal(again.evaluate(x), system.evaluate(x))


def test_shipped_rule_base_round_trips(tmp_path):
    fis = fuzzcore.load("rules/fuzzrisk.yaml")
    fis.save(tmp_path / "copy.yaml")
    assert fuzzcore.load(tmp_path / "copy.yaml") == fis
