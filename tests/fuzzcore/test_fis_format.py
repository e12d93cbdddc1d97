"""MATLAB .fis files (fuzzcore.fis_format): reading, writing, names, Sugeno, round trips, errors.

The files here are written by hand for these tests. The MATLAB reference systems in
``../shared/conformance`` are tested in test_conformance.py; the property test at the end
also mutates them when they are there.
"""
import argparse
import dataclasses
import re
import warnings

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import fuzzcore
from conftest import CONFORMANCE_DIR
from fuzzcore import FuzzySystem, Rule, RuleBaseError, Term, Variable, fis_format, yaml_format
from monitor.cli import convert
from strategies import mamdani_systems, sugeno_systems

# A Mamdani system as MATLAB's writefis lays it out, with kinds and settings off the defaults.
FAN = """\
[System]
Name='fan'
Type='mamdani'
Version=2.0
NumInputs=2
NumOutputs=1
NumRules=4
AndMethod='prod'
OrMethod='probor'
ImpMethod='prod'
AggMethod='sum'
DefuzzMethod='bisector'

[Input1]
Name='temp'
Range=[0 40]
NumMFs=3
MF1='cold':'trapmf',[-5 0 10 20]
MF2='warm':'gbellmf',[5 2 20]
MF3='hot':'sigmf',[0.5 30]

[Input2]
Name='humidity'
Range=[0 100]
NumMFs=2
MF1='dry':'zmf',[20 60]
MF2='wet':'smf',[40 80]

[Output1]
Name='speed'
Range=[0 100]
NumMFs=3
MF1='off':'trimf',[0 0 30]
MF2='medium':'gaussmf',[15 50]
MF3='full':'pimf',[60 90 100 110]

[Rules]
1 0, 1 (1) : 1
2 -1, 2 (0.75) : 1
3 2, 3 (1) : 2
0 2, -1 (0.5) : 1
"""

FAN_SYSTEM = FuzzySystem(
    name="fan",
    inputs=(
        Variable("temp", (0, 40), (Term("cold", "trapmf", (-5, 0, 10, 20)), Term("warm", "gbellmf", (5, 2, 20)),
                                   Term("hot", "sigmf", (0.5, 30)))),
        Variable("humidity", (0, 100), (Term("dry", "zmf", (20, 60)), Term("wet", "smf", (40, 80)))),
    ),
    outputs=(Variable("speed", (0, 100), (Term("off", "trimf", (0, 0, 30)), Term("medium", "gaussmf", (15, 50)),
                                          Term("full", "pimf", (60, 90, 100, 110)))),),
    rules=(Rule((1, 0), (1,), 1.0, "and"), Rule((2, -1), (2,), 0.75, "and"), Rule((3, 2), (3,), 1.0, "or"),
           Rule((0, 2), (-1,), 0.5, "and")),
    and_method="prod", or_method="probor", implication="prod", aggregation="sum", defuzzifier="bisector",
)

# The same system as real files write it: comments, blank lines, CRLF, no Version or Num* keys,
# fuzzylite's 1.000 numbers, names and kinds in other cases, spaces and commas, double quotes.
QUIRKY = "\r\n".join([
    "#Code automatically generated with some tool",
    "% a MATLAB comment",
    "",
    "[System]",
    "Name = 'fan'   % a trailing comment",
    "Type='Mamdani'",
    "andmethod='PROD'",
    'OrMethod="probor"',
    "ImpMethod='prod'",
    "AggMethod='sum'",
    "DefuzzMethod='Bisector'",
    "",
    "  [Input1]",
    "Name='temp'",
    "Range=[0.000 40.000]",
    "MF1='cold':'TRAPMF',[-5.000 0.000 10.000 20.000]",
    "MF2='warm':'GbellMF',[5, 2, 20]",
    "MF3 = 'hot' : 'sigmf' , [ 0.5 30 ]  # another trailing comment",
    "[Input2]",
    "Name='humidity'",
    "Range=[0,100]",
    "MF1='dry':'zmf',[20 60]",
    "MF2='wet':'smf',[40 80]",
    "[output1]",
    "Name='speed'",
    "Range=[0 100]",
    "NumMFs=3",
    "MF1='off':'trimf',[0 0 30]",
    "MF2='medium':'gaussmf',[15 50]",
    "MF3='full':'pimf',[6e1 90 100 110]",
    "",
    "[Rules]",
    "1.000 0.000 , 1.000 (1.000) : 1",
    "2 -1, 2 (0.75) : 1 % comment",
    "\t3 2,3(1):2",
    "0 2 , -1 (.5) : 1",
    "",
]) + "\r\n"

# A Sugeno system: a constant and a linear output (z = 2 x1 - x2 + 1), weights, don't care.
SUGENO = """\
[System]
Name='blend'
Type='sugeno'
Version=2.0
NumInputs=2
NumOutputs=1
NumRules=2
AndMethod='min'
OrMethod='max'
ImpMethod='prod'
AggMethod='sum'
DefuzzMethod='wtaver'

[Input1]
Name='x1'
Range=[0 10]
NumMFs=2
MF1='low':'trimf',[-10 0 10]
MF2='high':'trimf',[0 10 20]

[Input2]
Name='x2'
Range=[0 10]
NumMFs=1
MF1='any':'trapmf',[-1 0 10 11]

[Output1]
Name='z'
Range=[0 8]
NumMFs=2
MF1='flat':'constant',[3]
MF2='slope':'linear',[2 -1 1]

[Rules]
1 0, 1 (1) : 1
2 1, 2 (0.5) : 1
"""


def _loads(text, source="test.fis"):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # renamed names warn; the tests that care check it
        return fis_format.loads(text, source=source)


def _matlab_writable(system):
    return dataclasses.replace(system, resolution=101, no_rule_fired="midpoint")


# --------------------------------------------------------------------------- reading
def test_reads_every_field():
    assert fis_format.loads(FAN) == FAN_SYSTEM


def test_reads_what_real_files_contain():
    assert fis_format.loads(QUIRKY) == FAN_SYSTEM


def test_load_and_save_follow_the_extension(tmp_path):
    path = tmp_path / "fan.FIS"
    path.write_text(FAN)
    system = fuzzcore.load(path)
    assert system == FAN_SYSTEM
    system.save(tmp_path / "again.fis")
    assert (tmp_path / "again.fis").read_text() == FAN  # FAN is laid out exactly as the writer does


def test_missing_system_keys_take_matlab_defaults():
    rest = FAN.split("[Input1]")[1]
    text = "[System]\n\n[Input1]" + rest  # [System] holds no key at all
    system = fis_format.loads(text, source="some/dir/defaults.fis")
    assert (system.name, system.type, system.and_method, system.or_method, system.implication,
            system.aggregation, system.defuzzifier) == ("defaults", "mamdani", "min", "max", "min", "max",
                                                        "centroid")
    assert system.inputs == FAN_SYSTEM.inputs and system.rules == FAN_SYSTEM.rules
    sugeno = re.sub(r"^DefuzzMethod=.*\n", "", SUGENO, flags=re.M)
    assert fis_format.loads(sugeno).defuzzifier == "wtaver"


@pytest.mark.parametrize("name, usable", [
    ("speed", "speed"), ("Mid-Age", "Mid-Age"), ("x1.2", "x1.2"), ("_x", "_x"),
    ("Food Quality", "Food_Quality"), ("a  b/c", "a_b_c"), ("temp (°C)", "temp_C_"), ("1st", "_1st"),
    ("-x", "_-x"), (".5", "_.5"), ("not", "not_"), ("is", "is_"), ("é", "_"),
])
def test_rule_text_name(name, usable):
    assert fis_format.rule_text_name(name) == usable


def test_names_not_usable_in_rules_are_renamed_with_a_warning():
    text = (FAN.replace("Name='fan'", "Name='my fan: it''s \"big\" % #'")
            .replace("Name='temp'", "Name='air temp'")
            .replace("'hot':'sigmf'", "\"very hot\":'sigmf'"))
    with pytest.warns(UserWarning) as caught:
        system = fis_format.loads(text, source="names.fis")
    messages = [str(w.message) for w in caught]
    assert messages == [
        "names.fis: line 15: input 1 name 'air temp' is not usable in rule text; renamed 'air_temp'",
        "names.fis: line 20: input 1 MF3 name 'very hot' is not usable in rule text; renamed 'very_hot'",
    ]
    assert system.name == "my fan: it's \"big\" % #"  # the system's name is free text, kept as written
    assert system.input_names == ("air_temp", "humidity")
    assert system.inputs[0].terms[2].name == "very_hot"
    assert fis_format.loads(fis_format.dumps(system)) == system


def test_latin1_file_is_read(tmp_path):
    path = tmp_path / "latin.fis"
    path.write_bytes(FAN.replace("Name='fan'", "Name='Café'").replace("'temp'", "'température'")
                     .encode("latin-1"))
    with pytest.warns(UserWarning, match="renamed 'temp_rature'"):
        system = fuzzcore.load(path)
    assert system.name == "Café" and system.inputs[0].name == "temp_rature"


def test_repeated_term_names_bind_by_index(tmp_path):
    # two output terms named 'c': the rule picks the second by its index, never by name
    text = (SUGENO.replace("MF1='flat':'constant',[3]", "MF1='c':'constant',[3]")
            .replace("MF2='slope':'linear',[2 -1 1]", "MF2='c':'constant',[5]")
            .replace("1 0, 1 (1) : 1\n", "1 0, 2 (1) : 1\n"))
    system = fis_format.loads(text)
    assert [t.name for t in system.outputs[0].terms] == ["c", "c"]
    # at x1 = 0 only 'low' fires (rule 1, strength 1), so the output is the second 'c': 5
    assert system.infer(0.0, 4.0) == 5.0
    assert fis_format.loads(fis_format.dumps(system)) == system
    with pytest.raises(RuleBaseError, match=r"variable 'z' has repeated term names \(c\)") as info:
        fuzzcore.save(system, tmp_path / "out.yaml")
    assert info.value.source == str(tmp_path / "out.yaml")
    assert not (tmp_path / "out.yaml").exists()


# --------------------------------------------------------------------------- Sugeno
@pytest.mark.parametrize("defuzzifier", ["wtaver", "wtsum"])
def test_sugeno_constant_and_linear_outputs(defuzzifier):
    system = fis_format.loads(SUGENO.replace("'wtaver'", f"'{defuzzifier}'"))
    # at (x1, x2) = (2.5, 4): low = trimf(2.5; -10, 0, 10) = 0.75, high = trimf(2.5; 0, 10, 20) = 0.25,
    # any = 1; rule 1: 0.75 (x2 don't care), rule 2: min(0.25, 1) * weight 0.5
    w1, w2 = 0.75, 0.25 * 0.5
    z1, z2 = 3.0, 2 * 2.5 - 4.0 + 1  # constant p0; linear p1 x1 + p2 x2 + p0
    expected = (w1 * z1 + w2 * z2) / (w1 + w2) if defuzzifier == "wtaver" else w1 * z1 + w2 * z2
    assert system.infer(2.5, 4.0) == pytest.approx(expected, rel=1e-15)
    # the batch kernels over a grid (more rows than the parallel threshold), against the same formulas
    x1, x2 = (a.ravel() for a in np.meshgrid(np.linspace(0, 10, 41), np.linspace(0, 10, 41)))
    w1, w2 = (10 - x1) / 10, 0.5 * x1 / 10
    z1, z2 = 3.0, 2 * x1 - x2 + 1
    num, den = w1 * z1 + w2 * z2, w1 + w2
    expected = num / den if defuzzifier == "wtaver" else num
    np.testing.assert_allclose(system.evaluate(np.column_stack([x1, x2]))[:, 0], expected, rtol=0, atol=1e-13)


def test_sugeno_no_rule_fired_gives_the_midpoint():
    system = fis_format.loads(SUGENO)
    # x1 = -20 is outside both triangles (-10..10 and 0..20): no rule fires; MATLAB gives mid-range
    assert system.infer(-20.0, 5.0) == (0 + 8) / 2


# --------------------------------------------------------------------------- writing
def test_writes_matlab_layout():
    system = FuzzySystem(
        name="it's a test",
        inputs=(Variable("a", (0, 1), (Term("lo", "trimf", (0, 0, 1)), Term("hi", "trimf", (0, 1, 1)))),
                Variable("b", (-0.5, 2.5), (Term("mid", "gaussmf", (0.1, 1 / 3)),))),
        outputs=(Variable("y", (0, 10), (Term("small", "trapmf", (0, 0, 1e-7, 5)), Term("big", "linsmf", (5, 10)))),),
        rules=(Rule((1, -1), (1,), 1.0, "and"), Rule((2, 0), (2,), 0.25, "or"), Rule((0, 1), (-2,), 0.5, "and")),
    )
    assert fis_format.dumps(system) == """\
[System]
Name='it''s a test'
Type='mamdani'
Version=2.0
NumInputs=2
NumOutputs=1
NumRules=3
AndMethod='min'
OrMethod='max'
ImpMethod='min'
AggMethod='max'
DefuzzMethod='centroid'

[Input1]
Name='a'
Range=[0 1]
NumMFs=2
MF1='lo':'trimf',[0 0 1]
MF2='hi':'trimf',[0 1 1]

[Input2]
Name='b'
Range=[-0.5 2.5]
NumMFs=1
MF1='mid':'gaussmf',[0.1 0.3333333333333333]

[Output1]
Name='y'
Range=[0 10]
NumMFs=2
MF1='small':'trapmf',[0 0 1e-07 5]
MF2='big':'linsmf',[5 10]

[Rules]
1 -1, 1 (1) : 1
2 0, 2 (0.25) : 2
0 1, -2 (0.5) : 1
"""


def test_writes_inputs_without_terms():
    text = SUGENO.replace("NumMFs=1\nMF1='any':'trapmf',[-1 0 10 11]", "NumMFs=0").replace("2 1, 2", "2 0, 2")
    system = fis_format.loads(text)
    assert system.inputs[1].terms == ()
    assert fis_format.dumps(system) == text
    assert yaml_format.loads(yaml_format.dumps(system)) == system  # YAML writes it as "terms: {}"


@pytest.mark.parametrize("change, message", [
    ({"resolution": 201}, "resolution 201: MATLAB's evalfis defuzzifies on 101 points"),
    ({"no_rule_fired": "nan"}, "no_rule_fired 'nan': MATLAB returns the midpoint"),
    ({"no_rule_fired": 50.0}, "no_rule_fired 50.0: MATLAB returns the midpoint"),
    ({"defuzzifier": "centroid_exact", "aggregation": "max", "outputs": (Variable("speed", (0, 100), (
        Term("off", "trimf", (0, 0, 30)), Term("medium", "trimf", (20, 50, 80)),
        Term("full", "trapmf", (60, 90, 100, 110)))),)},
     "defuzzifier 'centroid_exact' is fuzzcore's own"),
    ({"name": "two\nlines"}, "has a line break"),
])
def test_refuses_what_matlab_would_evaluate_differently(tmp_path, change, message):
    system = dataclasses.replace(FAN_SYSTEM, **change)
    path = tmp_path / "out.fis"
    with pytest.raises(RuleBaseError, match=re.escape(message)) as info:
        system.save(path)
    assert info.value.source == str(path) and "cannot be written as a MATLAB .fis file" in str(info.value)
    assert not path.exists()


def test_description_and_metadata_ride_in_comment_lines():
    system = dataclasses.replace(FAN_SYSTEM, description="A fan.\nTwo lines: 'quoted' % #",
                                 metadata={"tuned": {"method": "pattern search", "folds": 5}, "cost": 0.125})
    text = fis_format.dumps(system)
    assert fis_format.loads(text) == system
    # what MATLAB reads (lines not starting with %) is the plain file
    matlab_view = "".join(line for line in text.splitlines(keepends=True) if not line.startswith("%"))
    assert matlab_view == FAN


@given(description=st.text(max_size=60),
       metadata=st.dictionaries(st.text(max_size=8),
                                st.one_of(st.integers(), st.floats(allow_nan=False), st.text(max_size=30),
                                          st.lists(st.integers(-5, 5), max_size=3), st.none()),
                                max_size=4))
def test_description_and_metadata_round_trip(description, metadata):
    system = dataclasses.replace(FAN_SYSTEM, description=description, metadata=metadata)
    assert fis_format.loads(fis_format.dumps(system)) == system


# --------------------------------------------------------------------------- round trips
def _with_conditions(system):
    """``system`` with every rule given at least one clause (YAML rules need a condition)."""
    rules = tuple(r if any(r.antecedent) else dataclasses.replace(r, antecedent=(1,) + r.antecedent[1:])
                  for r in system.rules)
    return dataclasses.replace(system, rules=rules)


@given(st.data())
def test_random_systems_round_trip_through_fis_and_yaml(data):
    system = _matlab_writable(data.draw(st.one_of(mamdani_systems(), sugeno_systems())))
    text = fis_format.dumps(system)
    back = fis_format.loads(text)
    assert back == system
    assert fis_format.dumps(back) == text
    # .fis -> YAML -> .fis keeps every number
    system = _with_conditions(system)
    via_yaml = yaml_format.loads(yaml_format.dumps(system))
    assert via_yaml == system
    assert fis_format.dumps(via_yaml) == fis_format.dumps(system)


def test_one_clause_or_rule_round_trips_through_yaml():
    text = FAN.replace("2 -1, 2 (0.75) : 1", "2 0, 2 (0.75) : 2")  # one clause, connective OR
    system = fis_format.loads(text)
    assert system.rules[1] == Rule((2, 0), (2,), 0.75, "or")
    yaml_text = yaml_format.dumps(system)
    assert "  - rule: if temp is warm then speed is medium\n    weight: 0.75\n    connective: or\n" in yaml_text
    back = yaml_format.loads(yaml_text)
    assert back == system and fis_format.dumps(back) == text


@pytest.mark.parametrize("rule, message", [
    ("{rule: if temp is warm and humidity is dry then speed is medium, connective: or}",
     "connective is for one-clause rules only"),
    ("{rule: if temp is warm then speed is medium, connective: xor}", "connective 'xor': expected 'and' or 'or'"),
])
def test_yaml_connective_key_is_checked(rule, message):
    yaml_text = yaml_format.dumps(FAN_SYSTEM) + f"  - {rule}\n"  # appended to the rule list
    with pytest.raises(RuleBaseError, match=re.escape(message)):
        yaml_format.loads(yaml_text)


def test_rule_without_condition_reads_but_cannot_cross_into_yaml(tmp_path):
    # MATLAB's AND rule with every input "don't care" always fires at its weight
    text = SUGENO.replace("2 1, 2 (0.5) : 1", "0 0, 2 (0.5) : 1")
    system = fis_format.loads(text)
    # at x1 = 0: rule 1 fires 1 (z = 3), rule 2 fires 0.5 (z = 2 * 0 - 4 + 1 = -3)
    assert system.infer(0.0, 4.0) == pytest.approx((1 * 3 + 0.5 * -3) / 1.5, rel=1e-15)
    assert fis_format.loads(fis_format.dumps(system)) == system
    with pytest.raises(RuleBaseError, match=r"rule 2 \(antecedent \[0, 0\]\).*no text form") as info:
        fuzzcore.save(system, tmp_path / "blend.yaml")
    assert info.value.source == str(tmp_path / "blend.yaml") and info.value.place == "rules[1]"


def test_metadata_aliases_stay_shared():
    # nested YAML aliases are not expanded into copies (eight levels of nine would be 9**8 lists)
    text = "%fuzzcore: metadata:\n%fuzzcore:   a: &a [1, 2]\n" + "".join(
        f"%fuzzcore:   {b}: &{b} [{', '.join(['*' + a] * 9)}]\n" for a, b in zip("abcdefgh", "bcdefghi")) + FAN
    metadata = fis_format.loads(text).metadata
    assert metadata["i"][0] is metadata["i"][8] and metadata["b"][0] is metadata["a"] == [1, 2]


def test_yaml_rule_base_with_nested_metadata_saves_as_fis_and_back(tmp_path):
    yaml_text = yaml_format.dumps(FAN_SYSTEM) + "metadata:\n  tuned: {method: pso, particles: 30}\n"
    (tmp_path / "in.yaml").write_text(yaml_text)
    system = fuzzcore.load(tmp_path / "in.yaml")
    system.save(tmp_path / "out.fis")
    system.save(tmp_path / "out.yaml")
    assert fuzzcore.load(tmp_path / "out.fis") == system == fuzzcore.load(tmp_path / "out.yaml")


# --------------------------------------------------------------------------- errors
def _cut(text, start, end=None):
    """``text`` without the lines from the one starting with ``start`` up to the one starting with ``end``."""
    lines = text.split("\n")
    i = next(k for k, line in enumerate(lines) if line.startswith(start))
    j = next(k for k, line in enumerate(lines) if line.startswith(end)) if end else len(lines)
    return "\n".join(lines[:i] + lines[j:])


# (id, file text, the line the error must name: the start of its text, its number, or None for the
# last line; a fragment of the message)
MALFORMED = [
    ("empty file", "", None, "the [System] section is missing"),
    ("no [System]", _cut(FAN, "[System]", "[Input1]"), "[Input1]", "the [System] section is missing"),
    ("no [Rules]", _cut(FAN, "[Rules]"), None, "the [Rules] section is missing"),
    ("no [Output1]", _cut(FAN, "[Output1]", "[Rules]"), "NumOutputs=1",
     "NumOutputs=1 but the file has 0 [OutputN] section(s)"),
    ("no output at all", _cut(FAN.replace("NumOutputs=1\n", ""), "[Output1]", "[Rules]"), "[System]",
     "no [Output1] section; a system needs at least one output"),
    ("NumInputs disagrees", FAN.replace("NumInputs=2", "NumInputs=3"), "NumInputs=3",
     "NumInputs=3 but the file has 2 [InputN] section(s)"),
    ("NumMFs disagrees", FAN.replace("NumMFs=3", "NumMFs=4", 1), "NumMFs=4",
     "NumMFs=4 but [Input1] lists 3 membership function(s)"),
    ("NumRules disagrees", FAN.replace("NumRules=4", "NumRules=5"), "NumRules=5",
     "NumRules=5 but [Rules] lists 4 rule(s)"),
    ("unknown MF type", FAN.replace("'gbellmf'", "'bellmf'"), "MF2='warm'",
     "unknown membership function 'bellmf'; expected one of trimf"),
    ("rule index out of range", FAN.replace("3 2, 3 (1) : 2", "4 2, 3 (1) : 2"), "4 2, 3",
     "rule antecedent index 4 for 'temp': expected 0 or +-1..+-3"),
    ("output index out of range", FAN.replace("3 2, 3 (1) : 2", "3 2, -4 (1) : 2"), "3 2, -4",
     "rule consequent index -4 for 'speed'"),
    ("non-numeric parameter", FAN.replace("[5 2 20]", "[5 two 20]"), "MF2='warm'", "'two' is not a number"),
    ("infinite parameter", FAN.replace("[5 2 20]", "[5 2 1e999]"), "MF2='warm'", "'1e999' is not a finite number"),
    ("too few parameters", FAN.replace("[0 0 30]", "[0 30]"), "MF1='off'", "trimf takes 3 parameters (a, b, c), got 2"),
    ("unsorted parameters", FAN.replace("[0 0 30]", "[30 0 0]"), "MF1='off'", "non-decreasing order"),
    ("non-positive width", FAN.replace("[15 50]", "[0 50]"), "MF2='medium'", "parameter 1 (a width) must be > 0"),
    ("reversed range", FAN.replace("Range=[0 40]", "Range=[40 0]"), "Range=[40 0]", "expected finite lo < hi"),
    ("range of three", FAN.replace("Range=[0 40]", "Range=[0 20 40]"), "Range=[0 20 40]", "expected [lo hi]"),
    ("range without brackets", FAN.replace("Range=[0 40]", "Range=0 40"), "Range=0 40",
     "expected numbers in brackets"),
    ("weight above 1", FAN.replace("(0.75)", "(1.5)"), "2 -1, 2 (1.5)", "rule weight 1.5: expected a number in [0, 1]"),
    ("connective 3", FAN.replace("(1) : 2", "(1) : 3"), "3 2, 3 (1) : 3", "expected 1 (AND) or 2 (OR)"),
    ("too few rule entries", FAN.replace("1 0, 1 (1) : 1", "1, 1 (1) : 1"), "1, 1 (1) : 1",
     "1 input index(es), expected 2 (one per input: temp, humidity)"),
    ("rule without punctuation", FAN.replace("1 0, 1 (1) : 1", "1 0 1 1 1"), "1 0 1 1 1",
     "expected 'a1 ... an, c1 ... cm (weight) : connective'"),
    ("hedge", FAN.replace("1 0, 1 (1) : 1", "1.5 0, 1 (1) : 1"), "1.5 0", "rule input index '1.5' is not an integer"),
    ("MF numbering", FAN.replace("MF2='warm'", "MF3='warm'"), "MF3='warm'", "expected MF2"),
    ("unknown key", FAN.replace("Version=2.0", "Version=2.0\nFoo=1"), "Foo=1", "unknown key 'Foo' in [System]"),
    ("unknown variable key", FAN.replace("Name='temp'", "Name='temp'\nUnit='C'"), "Unit=",
     "unknown key 'Unit' in [Input1]; expected Name, Range, NumMFs"),
    ("repeated key", FAN.replace("Type='mamdani'", "Type='mamdani'\nType='sugeno'"), "Type='sugeno'",
     "Type is given twice in [System] (first at line 3)"),
    ("not key=value", FAN.replace("Version=2.0", "Version 2.0"), "Version 2.0", "expected Key=value in [System]"),
    ("unknown section", FAN.replace("[Rules]", "[Extra]\n[Rules]"), "[Extra]", "unknown section [Extra]"),
    ("repeated section", FAN.replace("[Input2]", "[Input1]"), "[Input1]\nName='humidity'",
     "a second [Input1] section (the first is at line 14)"),
    ("section gap", FAN.replace("[Input2]", "[Input3]"), "[Input3]", "[Input3] but no [Input2]"),
    ("text before [System]", "Name='fan'\n" + FAN, "Name='fan'", "comes before any section"),
    ("unquoted name", FAN.replace("Name='fan'", "Name=fan"), "Name=fan", "expected a quoted string"),
    ("unterminated quote", FAN.replace("Name='temp'", "Name='temp"), "Name='temp", "expected a quoted string"),
    ("empty name", FAN.replace("Name='temp'", "Name=''"), "Name=''", "input 1 name is empty"),
    ("repeated variable name", FAN.replace("Name='humidity'", "Name='temp'"), 23,
     "variable name 'temp' is already used (line 15)"),
    ("custom AND", FAN.replace("AndMethod='prod'", "AndMethod='mymin'"), "AndMethod",
     "AndMethod 'mymin': expected one of min, prod"),
    ("Sugeno defuzzifier on Mamdani", FAN.replace("'bisector'", "'wtaver'"), "DefuzzMethod",
     "DefuzzMethod (for a mamdani system) 'wtaver': expected one of centroid, bisector, mom, som, lom"),
    ("fuzzcore-only defuzzifier", FAN.replace("'bisector'", "'centroid_exact'"), "DefuzzMethod",
     "'centroid_exact': expected one of centroid"),
    ("type-2", FAN.replace("'mamdani'", "'mamdanitype2'"), "Type=", "Type 'mamdanitype2': expected one of"),
    ("constant output in Mamdani", FAN.replace("'off':'trimf',[0 0 30]", "'off':'constant',[0]"), "MF1='off'",
     "constant is a Sugeno output kind, not usable on a Mamdani output"),
    ("linear input", SUGENO.replace("'any':'trapmf',[-1 0 10 11]", "'any':'linear',[1 2 3]"), "MF1='any'",
     "linear is a Sugeno output kind, not usable on an input"),
    ("membership function on Sugeno output", SUGENO.replace("'flat':'constant',[3]", "'flat':'trimf',[0 1 2]"),
     "MF1='flat'", "a Sugeno output must be 'constant' or 'linear'"),
    ("linear of the wrong length", SUGENO.replace("[2 -1 1]", "[2 1]"), "MF2='slope'",
     "linear takes 3 parameters (2 coefficients then p0), got 2"),
    ("negated Sugeno output", SUGENO.replace("2 1, 2 (0.5)", "2 1, -2 (0.5)"), "2 1, -2",
     "a Sugeno rule cannot negate its output term"),
    ("rule sets no output", FAN.replace("1 0, 1 (1) : 1", "1 0, 0 (1) : 1"), "1 0, 0", "rule sets no output"),
    ("no rules", FAN.replace("NumRules=4\n", "").split("[Rules]")[0] + "[Rules]\n", "[Rules]",
     "[Rules] lists no rule; expected at least one"),
    ("output without terms", FAN.replace("NumMFs=3\nMF1='off':'trimf',[0 0 30]\nMF2='medium':'gaussmf',[15 50]\n"
                                         "MF3='full':'pimf',[60 90 100 110]", "NumMFs=0"), "NumMFs=0",
     "output 'speed' has no membership functions"),
    ("text after the parameters", FAN.replace("[0 0 30]", "[0 0 30],'x'"), "MF1='off'",
     "expected 'name':'kind',[parameters]"),
    ("bad YAML in %fuzzcore lines", "%fuzzcore: description: [unclosed\n" + FAN, "%fuzzcore",
     "in the %fuzzcore: lines: not valid safe YAML"),
    ("unknown %fuzzcore key", "%fuzzcore: colour: red\n" + FAN, "%fuzzcore",
     "must hold a mapping with 'description' and/or 'metadata'"),
    ("duplicate %fuzzcore key", "%fuzzcore: description: a\n%fuzzcore: description: b\n" + FAN,
     "%fuzzcore: description: b", "duplicate key 'description'"),
    ("bad date in %fuzzcore lines", "%fuzzcore: metadata: {made: 2020-13-45}\n" + FAN, "%fuzzcore",
     "not valid safe YAML: month must be in 1..12"),
    ("split %fuzzcore lines", "%fuzzcore: description: a\n\n%fuzzcore: metadata: {}\n" + FAN, 2,
     "the %fuzzcore: lines must follow one another; line 2 breaks them"),
]


def _line_of(text, needle):
    lines = text.split("\n")
    if needle is None:
        return len(lines) - 1 if text.endswith("\n") else max(len(lines), 1)
    if isinstance(needle, int):
        return needle
    first = needle.split("\n")[0]
    return next(k for k, line in enumerate(lines, start=1)
                if line.startswith(first) and "\n".join(lines[k - 1:]).startswith(needle))


@pytest.mark.parametrize("text, needle, message", [m[1:] for m in MALFORMED], ids=[m[0] for m in MALFORMED])
def test_malformed_file_error_names_file_and_line(tmp_path, text, needle, message):
    path = tmp_path / "bad.fis"
    path.write_text(text)
    with pytest.raises(RuleBaseError) as info:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # nothing here should be a mere rename
            fuzzcore.load(path)
    error = info.value
    assert error.source == str(path)
    assert error.place == f"line {_line_of(text, needle)}", str(error)
    assert message in error.detail, str(error)
    assert str(error).startswith(f"{path}: line ")


# --------------------------------------------------------------------------- robustness
_BASES = [FAN, QUIRKY, SUGENO, fis_format.dumps(dataclasses.replace(FAN_SYSTEM, description="d", metadata={"k": [1]}))]
if CONFORMANCE_DIR.is_dir():  # MATLAB's demo systems, read in place (never copied)
    _BASES += [p.read_text() for p in sorted(CONFORMANCE_DIR.glob("*/*.fis"))]
_JUNK = st.sampled_from(["", "x", "nan", "Inf", "-", "1e999", "'", '"', "[", "]", ",", ":", "(", ")", "=", "%", "#",
                         "0", "-1", "99", "1.5", "1e308", "\r", "é", " ", "[Rules]", "[Input9]", "MF7=", "''"])


@st.composite
def _mutated_files(draw):
    lines = draw(st.sampled_from(_BASES)).split("\n")
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(("delete", "duplicate", "swap", "number", "insert", "truncate")))
        i = draw(st.integers(0, len(lines) - 1))
        line = lines[i]
        if op == "delete" and len(lines) > 1:
            del lines[i]
        elif op == "duplicate":
            lines.insert(draw(st.integers(0, len(lines))), line)
        elif op == "swap" and len(line) >= 2:
            k = draw(st.integers(0, len(line) - 2))
            lines[i] = line[:k] + line[k + 1] + line[k] + line[k + 2:]
        elif op == "number":
            numbers = list(re.finditer(r"-?\d+(?:\.\d+)?(?:e[+-]?\d+)?", line))
            if numbers:
                m = numbers[draw(st.integers(0, len(numbers) - 1))]
                lines[i] = line[:m.start()] + draw(_JUNK) + line[m.end():]
        elif op == "insert":
            k = draw(st.integers(0, len(line)))
            lines[i] = line[:k] + draw(_JUNK) + line[k:]
        elif op == "truncate":
            text = "\n".join(lines)
            lines = text[:draw(st.integers(0, len(text)))].split("\n")
    return "\n".join(lines)


_RANDOM_TEXT = st.text(alphabet=list("[]=':,()0123456789.-e \n\tSystemInputOutputRulesNameRangeMF%#"), max_size=300)


@settings(max_examples=300)
@given(text=st.one_of(_mutated_files(), _RANDOM_TEXT))
def test_random_and_mutated_files_raise_only_rule_base_errors(text):
    try:
        system = _loads(text, source="mutated.fis")
    except RuleBaseError as error:
        assert error.source == "mutated.fis"
        line = int(re.fullmatch(r"line (\d+)", error.place).group(1))
        assert 1 <= line <= max(len(re.split(r"\r\n|\r|\n", text)), 1)
        return
    # whatever is accepted is a valid system that saves and loads back equal
    assert fis_format.loads(fis_format.dumps(system)) == system


# --------------------------------------------------------------------------- command line
def _convert(*argv):
    parser = argparse.ArgumentParser()
    convert.add_arguments(parser)
    return convert.run(parser.parse_args([str(a) for a in argv]))


def test_convert_fis_to_yaml_and_back(tmp_path, capsys):
    (tmp_path / "fan.fis").write_text(FAN)
    assert _convert(tmp_path / "fan.fis", tmp_path / "fan.yaml") == 0
    assert "mamdani system 'fan', 2 input(s), 1 output(s), 4 rule(s)" in capsys.readouterr().out
    assert fuzzcore.load(tmp_path / "fan.yaml") == FAN_SYSTEM
    assert _convert(tmp_path / "fan.yaml", tmp_path / "back.fis") == 0
    assert (tmp_path / "back.fis").read_text() == FAN


def test_convert_reports_renamed_names(tmp_path, capsys):
    (tmp_path / "fan.fis").write_text(FAN.replace("Name='temp'", "Name='air temp'"))
    assert _convert(tmp_path / "fan.fis", tmp_path / "fan.yaml") == 0
    assert capsys.readouterr().err == (f"fuzzrisk convert: warning: {tmp_path / 'fan.fis'}: line 15: input 1 name "
                                       "'air temp' is not usable in rule text; renamed 'air_temp'\n")
    assert fuzzcore.load(tmp_path / "fan.yaml").input_names == ("air_temp", "humidity")


def test_convert_errors_name_the_file(tmp_path):
    (tmp_path / "bad.fis").write_text(FAN.replace("'gbellmf'", "'bellmf'"))
    with pytest.raises(RuleBaseError, match=r"bad\.fis: line 19: input 1 MF2: unknown membership function"):
        _convert(tmp_path / "bad.fis", tmp_path / "out.yaml")
    (tmp_path / "fan.fis").write_text(FAN)
    with pytest.raises(ValueError, match=r"out\.txt: unknown rule base format '\.txt'"):
        _convert(tmp_path / "fan.fis", tmp_path / "out.txt")
    with pytest.raises(ValueError, match=r"fan\.fis is the same file as .*fan\.fis, which is read"):
        _convert(tmp_path / "fan.fis", tmp_path / "fan.fis")
    assert (tmp_path / "fan.fis").read_text() == FAN
