"""Strict safe YAML: duplicate keys, deep nesting and unsafe tags refused with their lines,
mappings that know the lines of their keys."""
import pytest

from fuzzcore import strict_yaml
from fuzzcore.strict_yaml import MAX_DEPTH, LineDict, YamlError


def test_mappings_remember_their_lines():
    text = "a: 1\nb:\n  c: 2\n  d: [1, {e: 3}]\n"
    data = strict_yaml.load(text)
    assert data == {"a": 1, "b": {"c": 2, "d": [1, {"e": 3}]}}
    assert isinstance(data, LineDict) and isinstance(data["b"], LineDict)
    assert data.key_lines == {"a": 1, "b": 2}
    assert data["b"].key_lines == {"c": 3, "d": 4}  # the nested mapping starts on line 3
    assert data["b"].line == 3 and data["b"]["d"][1].line == 4


@pytest.mark.parametrize("text, line, detail", [
    ("a: 1\nb: 2\na: 3\n", 3, "duplicate key 'a' (first at line 1)"),
    ("top:\n  x: 1\n  y: 2\n  x: 1\n", 4, "duplicate key 'x' (first at line 2)"),
    ("a: !!python/object/apply:os.system [ls]\n", 1, "not valid safe YAML: could not determine a constructor"),
    ("a: [1, 2\n", 2, "not valid safe YAML"),
])
def test_refusals_name_the_line(text, line, detail):
    with pytest.raises(YamlError) as caught:
        strict_yaml.load(text)
    assert caught.value.line == line and caught.value.place == f"line {line}"
    assert caught.value.detail.startswith(detail) and str(caught.value).startswith(f"line {line}: {detail}")


def test_a_bad_value_without_a_line_is_still_a_yaml_error():
    with pytest.raises(YamlError, match="not valid safe YAML: month must be in 1..12") as caught:
        strict_yaml.load("when: 2024-13-01\n")
    assert caught.value.line is None and str(caught.value) == caught.value.detail


def test_nesting_is_limited_to_max_depth():
    # MAX_DEPTH lists inside each other read; one more is refused (at line 1: all on one line)
    deepest = []
    for _ in range(MAX_DEPTH - 1):
        deepest = [deepest]
    assert strict_yaml.load("[" * MAX_DEPTH + "]" * MAX_DEPTH) == deepest
    with pytest.raises(YamlError, match=f"nested more than {MAX_DEPTH} levels deep") as caught:
        strict_yaml.load("[" * (MAX_DEPTH + 1) + "]" * (MAX_DEPTH + 1))
    assert caught.value.line == 1
    # far deeper than Python's recursion limit: still the same error, not a RecursionError
    with pytest.raises(YamlError, match="nested more than"):
        strict_yaml.load("[" * 100_000 + "]" * 100_000)
