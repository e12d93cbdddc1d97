"""Hostile rule files (YAML and MATLAB .fis): garbage, mutations, cut-short files, degenerate terms.

The documented outcome for any file (:mod:`fuzzcore.yaml_format`, :mod:`fuzzcore.fis_format`):
a valid :class:`~fuzzcore.FuzzySystem`, or a :class:`~fuzzcore.RuleBaseError` whose message
starts with the file's path. A file that was cut short is always refused (YAML written by
fuzzcore: the end line; ``.fis`` written by fuzzcore: its counts and brackets), and
saving replaces a file whole or not at all.
"""
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import fuzzcore
from fuzzcore import FuzzySystem, RuleBaseError, yaml_format

ROOT = Path(__file__).resolve().parents[2]
RULES = ROOT / "rules" / "fuzzrisk.yaml"

GOOD = """\
inputs:
  x:
    range: [0, 1]
    terms:
      low: [trimf, 0, 0, 1]
      high: [trimf, 0, 1, 1]
outputs:
  y:
    range: [0, 1]
    terms:
      low: [trimf, 0, 0, 1]
      high: [trimf, 0, 1, 1]
rules:
  - if x is low then y is low
  - if x is high then y is high
"""


def _outcome(path: Path):
    """Load ``path``; the documented outcomes only: a system, or a RuleBaseError naming the file."""
    try:
        return fuzzcore.load(path)
    except RuleBaseError as exc:
        assert str(exc).startswith(f"{path}: "), str(exc)
        assert exc.source == str(path)
        return exc


def _saved(tmp_path, suffix):
    fis = fuzzcore.load(RULES)
    path = tmp_path / f"saved{suffix}"
    fis.save(path)
    return fis, path, path.read_bytes()


# --------------------------------------------------------------------------- item 11: cut short
@pytest.mark.parametrize("suffix", [".yaml", ".fis"])
def test_every_cut_short_saved_file_is_refused(tmp_path, suffix):
    fis, path, data = _saved(tmp_path, suffix)
    assert fuzzcore.load(path) == fis
    text = data.decode()
    cut = tmp_path / f"cut{suffix}"
    # every line boundary (the shapes an interrupted write leaves), and a cut inside each line
    ends = [k for k in range(len(text)) if text[k] == "\n"] + [k + 3 for k in range(len(text)) if text[k] == "\n"]
    for end in sorted(set(e for e in ends if 0 < e < len(text) - 1)):
        cut.write_text(text[:end])
        outcome = _outcome(cut)
        assert isinstance(outcome, RuleBaseError), f"cut at {end} of {len(text)} loaded: {text[max(0, end - 40):end]!r}"


def test_a_truncated_yaml_file_names_the_end_line(tmp_path):
    _, path, data = _saved(tmp_path, ".yaml")
    text = data.decode()
    # keep the first 3 of 9 rules: still valid YAML, which loaded before as a 3-rule system
    rules_at = text.index("rules:\n")
    three = text[:rules_at] + "".join(text[rules_at:].splitlines(keepends=True)[:4])
    path.write_text(three)
    with pytest.raises(RuleBaseError, match="no closing line '# end of rule base': it was cut short") as caught:
        fuzzcore.load(path)
    assert str(caught.value).startswith(str(path))


def test_files_without_the_header_need_no_end_line(tmp_path):
    path = tmp_path / "hand.yaml"
    path.write_text(GOOD)
    assert len(fuzzcore.load(path).rules) == 2


def test_save_replaces_a_file_whole_or_not_at_all(tmp_path):
    """A write that fails part-way (here the file-size limit, as a full disk would) leaves the
    old file as it was and no temporary file behind; before, the old file was cut short."""
    fis = fuzzcore.load(RULES)
    target = tmp_path / "rules.yaml"
    target.write_text(GOOD)
    script = textwrap.dedent(f"""
        import resource, signal, sys
        sys.path.insert(0, {str(ROOT)!r})
        import fuzzcore
        fis = fuzzcore.load({str(RULES)!r})
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (200, 200))
        try:
            fis.save({str(target)!r})
        except OSError as exc:
            print("failed:", exc.errno)
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=ROOT)
    assert "failed:" in done.stdout, done.stdout + done.stderr
    assert target.read_text() == GOOD
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rules.yaml"]
    fis.save(target)  # and without the limit it is replaced
    assert fuzzcore.load(target) == fis


def test_save_keeps_the_permissions_of_the_file_it_replaces(tmp_path):
    target = tmp_path / "rules.yaml"
    target.write_text(GOOD)
    os.chmod(target, 0o640)
    fuzzcore.load(RULES).save(target)
    assert os.stat(target).st_mode & 0o777 == 0o640


# --------------------------------------------------------------------------- random bytes and mutations
@settings(max_examples=80, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.binary(max_size=400), suffix=st.sampled_from([".yaml", ".fis"]))
def test_random_bytes_give_a_system_or_an_error_naming_the_file(tmp_path, data, suffix):
    path = tmp_path / f"random{suffix}"
    path.write_bytes(data)
    _outcome(path)


@settings(max_examples=80, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(suffix=st.sampled_from([".yaml", ".fis"]), edits=st.lists(
    st.tuples(st.sampled_from(["flip", "delete_line", "duplicate_line"]), st.integers(0, 10**6), st.integers(0, 255)),
    min_size=1, max_size=4))
def test_mutated_valid_files_give_a_system_or_an_error_naming_the_file(tmp_path, suffix, edits):
    _, path, data = _saved(tmp_path, suffix)
    data = bytearray(data)
    for op, where, byte in edits:
        if op == "flip":
            data[where % len(data)] = byte
        else:
            lines = bytes(data).split(b"\n")
            k = where % len(lines)
            lines[k:k + 1] = [] if op == "delete_line" else [lines[k], lines[k]]
            data = bytearray(b"\n".join(lines))
    path.write_bytes(bytes(data))
    outcome = _outcome(path)
    if isinstance(outcome, FuzzySystem):  # whatever it is, it evaluates
        outcome.infer(*[0.5 * sum(v.range) for v in outcome.inputs])


# --------------------------------------------------------------------------- item 13: deep nesting
@pytest.mark.parametrize("text", [
    "[" * 5000 + "]" * 5000,
    "inputs: " + "[" * 3000 + "]" * 3000 + "\n",
    "metadata: " + "{a: " * 2000 + "1" + "}" * 2000 + "\n",
    "".join(" " * k + "a:\n" for k in range(400)) + " " * 400 + "1\n",
])
def test_deep_nesting_is_a_clear_error_not_a_recursion_error(tmp_path, text):
    path = tmp_path / "deep.yaml"
    path.write_text(text)
    with pytest.raises(RuleBaseError, match="nested more than 32 levels deep") as caught:
        fuzzcore.load(path)
    assert str(caught.value).startswith(f"{path}: line ")


def test_deep_nesting_in_fuzzcore_lines_of_a_fis_file(tmp_path):
    fis = fuzzcore.load(RULES)
    path = tmp_path / "deep.fis"
    fis.save(path)
    text = path.read_text()
    path.write_text("%fuzzcore: metadata: " + "[" * 3000 + "]" * 3000 + "\n"
                    + "\n".join(line for line in text.splitlines() if not line.startswith("%fuzzcore:")) + "\n")
    with pytest.raises(RuleBaseError, match="nested more than 32 levels deep") as caught:
        fuzzcore.load(path)
    assert str(caught.value).startswith(f"{path}: ")


# --------------------------------------------------------------------------- item 4: degenerate terms
DEGENERATE = [  # kind, parameters, the value named, why
    ("gaussmf", [1e-200, 0.5], "= 1e-200", r"parameter 1 \(sigma, a width\)"),
    ("gaussmf", [1e200, 0.5], "= 1e+200", r"parameter 1 \(sigma, a width\)"),
    ("gauss2mf", [0.1, 0.2, 1e-160, 0.6], "= 1e-160", r"parameter 3 \(sigma, a width\)"),
    ("gbellmf", [1e-200, 2, 0.5], "= 1e-200", r"parameter 1 \(a, a width\)"),
    ("trimf", [-1e308, 0, 1e308], "-1e+308", "differences of parameters overflow"),
    ("sigmf", [10, 1e308], "1e+308", "differences of parameters overflow"),
]


@pytest.mark.parametrize("kind, params, value, words", DEGENERATE, ids=lambda v: str(v)[:20])
def test_degenerate_terms_are_refused_naming_file_term_and_value(tmp_path, kind, params, value, words):
    yaml_path = tmp_path / "bad.yaml"
    written = ", ".join(f"{p:.6e}" for p in params)  # YAML 1.1 floats: a dot and a signed exponent
    yaml_path.write_text(GOOD.replace("high: [trimf, 0, 1, 1]\noutputs", f"high: [{kind}, {written}]\noutputs"))
    with pytest.raises(RuleBaseError, match=words) as caught:
        fuzzcore.load(yaml_path)
    message = str(caught.value)
    assert message.startswith(f"{yaml_path}: line 6, inputs.x.terms.high") and value in message
    # the same term in a .fis file
    fis_text = ("[System]\nName='t'\n[Input1]\nName='x'\nRange=[0 1]\n"
                f"MF1='high':'{kind}',[{' '.join(map(repr, params))}]\n"
                "[Output1]\nName='y'\nRange=[0 1]\nMF1='a':'trimf',[0 0 1]\n[Rules]\n1, 1 (1) : 1\n")
    fis_path = tmp_path / "bad.fis"
    fis_path.write_text(fis_text)
    with pytest.raises(RuleBaseError, match=words) as caught:
        fuzzcore.load(fis_path)
    assert str(caught.value).startswith(f"{fis_path}: line 6: input 1 MF1") and value in str(caught.value)


def test_gaussmf_sigma_1e_200_names_the_value(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(GOOD.replace("high: [trimf, 0, 1, 1]\noutputs", "high: [gaussmf, 1.0e-200, 0.5]\noutputs"))
    with pytest.raises(RuleBaseError, match=r"parameter 1 \(sigma, a width\) = 1e-200 is degenerate"):
        fuzzcore.load(path)


def test_a_range_whose_width_overflows_is_refused(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(GOOD.replace("range: [0, 1]", "range: [-1.0e+308, 1.0e+308]", 1))
    with pytest.raises(RuleBaseError, match="its width hi - lo overflows"):
        fuzzcore.load(path)


# --------------------------------------------------------------------------- item 17: messages
def test_non_utf8_yaml_names_the_file_and_line(tmp_path):
    path = tmp_path / "latin.yaml"
    path.write_bytes(GOOD.replace("inputs:", "# caf\xe9\ninputs:").encode("latin-1"))
    with pytest.raises(RuleBaseError, match=r"not UTF-8 text: byte e9 at offset 5") as caught:
        fuzzcore.load(path)
    assert str(caught.value).startswith(f"{path}: line 1: ")


def test_an_integer_too_large_for_a_float_is_named(tmp_path):
    path = tmp_path / "big.yaml"
    path.write_text(GOOD.replace("range: [0, 1]", "range: [0, 1" + "0" * 400 + "]", 1))
    with pytest.raises(RuleBaseError, match=r"\(401 digits\) is too large for a float64") as caught:
        fuzzcore.load(path)
    assert str(caught.value).startswith(f"{path}: line 3, inputs.x.range")


def test_yaml11_exponent_text_is_explained(tmp_path):
    path = tmp_path / "e.yaml"
    path.write_text(GOOD.replace("range: [0, 1]", "range: [0, 1000]", 1).replace("low: [trimf, 0, 0, 1]",
                                                                                 "low: [trimf, 0, 0, 1e3]", 1))
    with pytest.raises(RuleBaseError) as caught:
        fuzzcore.load(path)
    message = str(caught.value)
    assert "'1e3' is not a finite number; YAML 1.1" in message and "takes 1e3 as text" in message
    assert message.endswith("write 1000.0")


def test_an_output_with_no_terms_says_so(tmp_path):
    path = tmp_path / "empty.yaml"
    path.write_text(GOOD.replace("""  y:
    range: [0, 1]
    terms:
      low: [trimf, 0, 0, 1]
      high: [trimf, 0, 1, 1]""", """  y:
    range: [0, 1]
    terms: {}"""))
    with pytest.raises(RuleBaseError, match=r"output 'y' has no terms \(terms: \{\}\)") as caught:
        fuzzcore.load(path)
    assert "has no term 'low'" not in str(caught.value)
    assert str(caught.value).startswith(f"{path}: line 10, outputs.y.terms")


def test_the_end_line_is_what_dumps_writes():
    fis = fuzzcore.load(RULES)
    text = yaml_format.dumps(fis)
    assert text.splitlines()[0] == yaml_format.HEADER and text.splitlines()[-1] == yaml_format.END
    assert yaml_format.loads(text) == fis
