"""Strict safe YAML: the one YAML reader of the project's hand-written files.

Rule bases (:mod:`fuzzcore.yaml_format`), the ``%fuzzcore:`` lines of ``.fis`` files and
camera calibration files (:mod:`monitor.datasets.calibration`) are read by :func:`load`:
YAML's safe loader (a tag that would construct an object is refused), plus

- a key given twice in one mapping is an error naming both lines, not last-one-wins;
- nesting deeper than :data:`MAX_DEPTH` lists or mappings is an error, not a
  ``RecursionError`` (PyYAML composes nested nodes recursively);
- every mapping is a :class:`LineDict` that remembers its line and its keys' lines, so
  that a reader's errors can name the line of a bad entry.

Any failure is a :class:`YamlError` naming the line where YAML knows it.
"""
from __future__ import annotations

from typing import Any

import yaml

#: deepest nesting of YAML collections read (a rule base needs 5; metadata a few more)
MAX_DEPTH = 32


class YamlError(ValueError):
    """Text that :func:`load` refuses; ``line`` (1-based) is None where YAML does not know it.

    The message is ``line N: detail`` (or ``detail``); readers prefix their file name.
    """

    def __init__(self, detail: str, line: int | None = None):
        self.detail = detail
        self.line = line
        super().__init__(f"{self.place}: {detail}" if line else detail)

    @property
    def place(self) -> str | None:
        """``"line N"``, or None."""
        return f"line {self.line}" if self.line else None


class LineDict(dict):
    """A mapping read from YAML that remembers the line of itself and of each key (1-based)."""

    line: int = 0
    key_lines: dict


class _StrictLoader(yaml.SafeLoader):
    """Safe loading, plus: duplicate keys are errors, mappings remember their lines, nesting
    deeper than :data:`MAX_DEPTH` is an error."""

    _depth = 0

    def compose_node(self, parent, index):
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                mark = self.peek_event().start_mark
                raise YamlError(f"lists or mappings nested more than {MAX_DEPTH} levels deep; a hand-written "
                                "file needs a handful", mark.line + 1)
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def construct_yaml_map(self, node):
        data = LineDict()
        data.line = node.start_mark.line + 1
        data.key_lines = {}
        yield data
        self.flatten_mapping(node)
        for key_node, value_node in node.value:
            key = self.construct_object(key_node, deep=True)
            line = key_node.start_mark.line + 1
            if key in data.key_lines:
                raise YamlError(f"duplicate key {key!r} (first at line {data.key_lines[key]})", line)
            data.key_lines[key] = line
            data[key] = self.construct_object(value_node, deep=True)


_StrictLoader.add_constructor("tag:yaml.org,2002:map", _StrictLoader.construct_yaml_map)


def load(text: str) -> Any:
    """Read YAML text strictly (see the module docstring); mappings are :class:`LineDict`.

    Raises
    ------
    YamlError
        Invalid YAML, an unsafe tag, a duplicate key, nesting deeper than
        :data:`MAX_DEPTH`, or a value PyYAML's constructors refuse (a bad date, ...).
    """
    try:
        return yaml.load(text, Loader=_StrictLoader)
    except YamlError:
        raise
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        problem = getattr(exc, "problem", None) or str(exc)
        raise YamlError(f"not valid safe YAML: {problem}", mark.line + 1 if mark else None) from None
    except (ValueError, TypeError, AttributeError) as exc:  # PyYAML's constructors: a bad date, !!int x, ...
        raise YamlError(f"not valid safe YAML: {exc}") from None
