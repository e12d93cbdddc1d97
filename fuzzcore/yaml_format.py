"""YAML rule bases: a strict safe reader and a readable writer.

Schema (every key but ``inputs``, ``outputs`` and ``rules`` is optional)::

    name: fuzzrisk
    description: free text
    type: mamdani                  # or sugeno
    and: min                       # min | prod
    or: max                        # max | probor
    implication: min               # min | prod            (Mamdani)
    aggregation: max               # max | sum | probor    (Mamdani)
    defuzzifier: centroid          # centroid | centroid_exact | bisector | mom | som | lom
                                   # (Mamdani); wtaver | wtsum (Sugeno)
    resolution: 101                # output grid points, both ends included (MATLAB: 101)
    no_rule_fired: midpoint        # midpoint | nan | a number
    metadata: {...}                # free provenance, kept on save/load
    inputs:
      iou:
        range: [0, 1]
        terms:
          low: [trapmf, 0, 0, 0.2, 0.4]     # [kind, parameters...] in MATLAB's order
    outputs:
      risk: {range: [0, 1], terms: {...}}
    rules:
      - if rdd is high then risk is high
      - rule: if rdd is low and iou is high then risk is low
        weight: 0.5
      - rule: if rdd is high then risk is high
        connective: or             # one-clause rules only: the connective MATLAB keeps
                                   # (``: 2`` in a .fis rule line); it does not change the result

Reading uses :func:`fuzzcore.strict_yaml.load` (YAML's safe loader; duplicate keys and
nesting deeper than :data:`~fuzzcore.strict_yaml.MAX_DEPTH` levels refused), refuses
unknown keys and text that is not UTF-8, and reports errors with the file, the line and
the YAML path of the offending entry.

Cut-short files. :func:`dumps` opens the text with :data:`HEADER` and closes it with the
line :data:`END`. A file that starts with the header but has no end line was cut short (an
interrupted copy or write: the file can hold 3 of its 9 rules and still be valid YAML) and
is refused. Files without the header (written by hand, or by an older fuzzcore) need no
end line: their only safeguard is YAML's own syntax and the checks above. A marker, rather
than a count or checksum in the file, because rule bases are meant to be edited by hand:
adding a rule must not break the file. A user who removes the end line while editing is
told to put it back or remove the header.
"""
from __future__ import annotations

import math
import numbers
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import yaml

from . import strict_yaml
from .strict_yaml import LineDict
from .errors import RuleBaseError
from .membership import check_params, resolve_kind
from .rules import CONNECTIVES, Rule, format_rule, parse_rule
from .system import FuzzySystem
from .variables import Term, Variable

_SETTINGS = {
    "and": "and_method", "or": "or_method", "implication": "implication",
    "aggregation": "aggregation", "defuzzifier": "defuzzifier", "resolution": "resolution",
    "no_rule_fired": "no_rule_fired", "type": "type", "name": "name", "description": "description",
}
_TOP_KEYS = set(_SETTINGS) | {"inputs", "outputs", "rules", "metadata"}
#: first line of a file :func:`dumps` writes; such a file must contain the line :data:`END`
HEADER = "# fuzzy rule base (fuzzcore YAML; see fuzzcore/yaml_format.py for the schema); it ends with the line below"
#: last line of a file :func:`dumps` writes
END = "# end of rule base"


#: the largest finite float64, as an integer (a larger YAML integer cannot be a parameter)
_LARGEST = int(sys.float_info.max)
#: why a number-looking text such as 1e3 is text to YAML 1.1, and how to write it
_YAML11_HINT = ("; YAML 1.1 (which PyYAML reads) takes {value} as text, not a number: exponent notation needs "
                "a dot in the mantissa and a signed exponent (1.0e+3, not 1e3 or 1.0e3); write {number}")


class _Reader:
    def __init__(self, source: str | None):
        self.source = source

    def error(self, message: str, path: str, where: Any = None, key: Any = None) -> RuleBaseError:
        line = None
        if isinstance(where, LineDict):
            line = where.key_lines.get(key, where.line) if key is not None else where.line
        place = f"line {line}, {path}" if line else path
        return RuleBaseError(message, source=self.source, place=place)

    def mapping(self, value: Any, path: str, allowed: set[str], required: set[str] = frozenset(),
                parent: Any = None, key: Any = None) -> LineDict:
        if not isinstance(value, dict):
            raise self.error(f"expected a mapping, got {type(value).__name__} {value!r}", path, parent, key)
        unknown = sorted(str(k) for k in value if k not in allowed)
        if unknown:
            raise self.error(f"unknown key(s) {', '.join(unknown)}; expected {', '.join(sorted(allowed))}",
                             path, value, unknown[0])
        missing = sorted(required - set(value))
        if missing:
            raise self.error(f"missing key(s) {', '.join(missing)}", path, value)
        return value

    def number(self, value: Any, path: str, parent: Any, key: Any) -> float:
        if isinstance(value, int) and not isinstance(value, bool) and abs(value) > _LARGEST:
            raise self.error(f"the integer {str(value)[:20]}... ({len(str(abs(value)))} digits) is too large for a "
                             "float64 (|x| < 1.8e308)", path, parent, key)
        if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
            hint = ""
            if isinstance(value, str):
                try:
                    hint = _YAML11_HINT.format(value=value, number=_scalar(float(value)))
                except ValueError:
                    pass
            raise self.error(f"{value!r} is not a finite number{hint}", path, parent, key)
        return float(value)

    def variable(self, name: Any, spec: Any, path: str, parent: LineDict) -> Variable:
        spec = self.mapping(spec, path, {"range", "terms"}, {"range", "terms"}, parent, name)
        rng = spec["range"]
        if not isinstance(rng, list) or len(rng) != 2:
            raise self.error(f"range {rng!r}: expected [lo, hi]", f"{path}.range", spec, "range")
        lo, hi = (self.number(v, f"{path}.range", spec, "range") for v in rng)
        terms = spec["terms"]
        if not isinstance(terms, dict):
            raise self.error("terms: expected a mapping of name: [kind, parameters...]",
                             f"{path}.terms", spec, "terms")
        built = []
        for term_name, term_spec in terms.items():
            tpath = f"{path}.terms.{term_name}"
            if not isinstance(term_spec, list) or not term_spec or not isinstance(term_spec[0], str):
                raise self.error(f"{term_spec!r}: expected [kind, parameters...], e.g. [trimf, 0, 0.5, 1]",
                                 tpath, terms, term_name)
            params = [self.number(v, tpath, terms, term_name) for v in term_spec[1:]]
            try:
                term = Term(term_name, term_spec[0], params)
            except (RuleBaseError, ValueError) as exc:
                raise self.error(getattr(exc, "detail", str(exc)), tpath, terms, term_name) from None
            kind = resolve_kind(term.kind)
            problem = None if kind.n_params is None else check_params(kind, term.params)  # linear: in the system
            if problem:
                raise self.error(f"{kind.name} {list(term.params)}: {problem}", tpath, terms, term_name)
            built.append(term)
        try:
            return Variable(name, (lo, hi), tuple(built))
        except RuleBaseError as exc:
            raise self.error(exc.detail, path, parent, name) from None

    def connective(self, rule: Rule, value: Any, path: str, item: LineDict) -> Rule:
        """``rule`` with the connective an explicit ``connective:`` key gives a one-clause rule."""
        if value not in CONNECTIVES:
            raise self.error(f"connective {value!r}: expected 'and' or 'or'", path, item, "connective")
        if sum(1 for index in rule.antecedent if index) > 1:
            raise self.error("connective is for one-clause rules only; this rule's text already joins its "
                             f"clauses with {rule.connective!r}", path, item, "connective")
        return replace(rule, connective=value)

    def variables(self, data: LineDict, key: str) -> tuple[Variable, ...]:
        spec = data[key]
        if not isinstance(spec, dict) or not spec:
            raise self.error("expected a non-empty mapping of variable name: {range, terms}", key, data, key)
        variables = tuple(self.variable(name, value, f"{key}.{name}", spec) for name, value in spec.items())
        for var in variables:  # before the rules, which would report a missing term
            if key == "outputs" and not var.terms:
                raise self.error(f"output {var.name!r} has no terms (terms: {{}}); an output needs at least one "
                                 "term for rules to conclude", f"{key}.{var.name}.terms", spec[var.name], "terms")
        return variables

    def system(self, data: Any) -> FuzzySystem:
        if data is None:
            raise self.error("the file is empty; expected a rule base mapping", "top level")
        data = self.mapping(data, "top level", _TOP_KEYS, {"inputs", "outputs", "rules"})
        inputs, outputs = self.variables(data, "inputs"), self.variables(data, "outputs")
        rules_spec = data["rules"]
        if not isinstance(rules_spec, list) or not rules_spec:
            raise self.error("expected a non-empty list of rules", "rules", data, "rules")
        rules = []
        for r, item in enumerate(rules_spec):
            path = f"rules[{r}]"
            weight, connective = 1.0, None
            if isinstance(item, dict):
                self.mapping(item, path, {"rule", "weight", "connective"}, {"rule"})
                weight = self.number(item.get("weight", 1.0), f"{path}.weight", item, "weight")
                text = item["rule"]
                connective = item.get("connective")
            else:
                text = item
            try:
                rule = parse_rule(text, inputs, outputs, weight)
            except RuleBaseError as exc:
                raise self.error(exc.detail, path, data, "rules") from None
            if connective is not None:
                rule = self.connective(rule, connective, f"{path}.connective", item)
            rules.append(rule)
        settings = {attr: data[key] for key, attr in _SETTINGS.items() if key in data}
        settings.setdefault("name", Path(self.source).stem if self.source else "fuzzy-system")
        if "metadata" in data:
            settings["metadata"] = _plain(self.mapping(data["metadata"], "metadata", set(data["metadata"] or {}),
                                                       parent=data, key="metadata"))
        if settings.get("type") == "sugeno":
            settings.setdefault("defuzzifier", "wtaver")
        try:
            return FuzzySystem(inputs=inputs, outputs=outputs, rules=tuple(rules), **settings)
        except RuleBaseError as exc:
            key = (exc.place or "").split(".")[0].split("[")[0]
            key = {v: k for k, v in _SETTINGS.items()}.get(key, key)
            raise self.error(exc.detail, exc.place or "top level", data, key if key in data else None) from None


def _parse(text: str, source: str | None) -> Any:
    """Strict safe YAML (:func:`fuzzcore.strict_yaml.load`); any failure is a :class:`RuleBaseError`."""
    lines = text.splitlines()
    if lines and lines[0].rstrip() == HEADER and END not in (line.rstrip() for line in lines):
        raise RuleBaseError(f"the file starts with fuzzcore's header line but has no closing line {END!r}: it was "
                            "cut short (an interrupted copy or write) and may have lost rules. Restore it from a "
                            "copy; if you removed the line while editing, put it back at the end (or remove the "
                            "first line)", source=source, place=f"line {len(lines)}")
    try:
        return strict_yaml.load(text)
    except strict_yaml.YamlError as exc:
        raise RuleBaseError(exc.detail, source=source, place=exc.place) from None


def _plain(data: Any) -> Any:
    """``data`` with every :class:`LineDict` turned into a plain dict (which YAML can dump again).

    Containers that YAML aliases share stay shared, so nested aliases cannot blow up into
    exponentially many copies (the strict loader already refuses recursive ones).
    """
    done: dict[int, Any] = {}

    def convert(value: Any) -> Any:
        if not isinstance(value, (dict, list)):
            return value
        if id(value) not in done:
            done[id(value)] = ({k: convert(v) for k, v in value.items()} if isinstance(value, dict)
                               else [convert(v) for v in value])
        return done[id(value)]

    return convert(data)


def load_data(text: str, source: str | None = None) -> Any:
    """Plain Python data from YAML text, read as rule bases are (safe, duplicate keys refused).

    For YAML carried inside other files (the ``%fuzzcore:`` lines of a ``.fis`` file).
    Errors are :class:`RuleBaseError` naming ``source`` and the line.
    """
    return _plain(_parse(text, source))


def loads(text: str, source: str | None = None) -> FuzzySystem:
    """Read a rule base from YAML text; ``source`` names it in error messages."""
    return _Reader(source).system(_parse(text, source))


def decode(data: bytes, source: str) -> str:
    """UTF-8 text of a file's bytes (a byte-order mark dropped); :class:`RuleBaseError` naming
    ``source``, the line and the byte when it is not UTF-8."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise RuleBaseError(f"not UTF-8 text: byte {data[exc.start:exc.start + 1].hex(' ')!s} at offset "
                            f"{exc.start} cannot be decoded ({exc.reason}); save the file as UTF-8",
                            source=source, place=f"line {line}") from None


def read(path: str | Path) -> FuzzySystem:
    """Read a YAML rule base file (UTF-8)."""
    path = Path(path)
    return loads(decode(path.read_bytes(), str(path)), source=str(path))


def _scalar(value: Any) -> str:
    """One YAML scalar, quoted only where YAML needs it (names like ``no`` or ``on``)."""
    # ASCII with escapes: with allow_unicode, line-break characters such as U+0085 are written
    # raw and read back as spaces
    text = yaml.safe_dump(value, width=10**9, allow_unicode=False)
    return text[: -len("\n...\n")] if text.endswith("\n...\n") else text.rstrip("\n")


def _variable_lines(var: Variable) -> list[str]:
    names = [t.name for t in var.terms]
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise RuleBaseError(f"variable {var.name!r} has repeated term names ({', '.join(repeated)}); "
                            "YAML rule bases name terms uniquely: rename them first")
    lines = [f"  {_scalar(var.name)}:", f"    range: [{_scalar(var.range[0])}, {_scalar(var.range[1])}]",
             "    terms:" if var.terms else "    terms: {}"]  # an input may have no terms
    for term in var.terms:
        params = ", ".join(_scalar(p) for p in term.params)
        lines.append(f"      {_scalar(term.name)}: [{term.kind}, {params}]")
    return lines


def dumps(system: FuzzySystem) -> str:
    """The YAML text of ``system``; :func:`loads` reads it back equal."""
    lines = [HEADER]
    lines.append(f"name: {_scalar(system.name)}")
    if system.description:
        lines.append(f"description: {_scalar(system.description)}")
    lines.append(f"type: {system.type}")
    lines.append(f"and: {system.and_method}")
    lines.append(f"or: {system.or_method}")
    lines.append(f"implication: {system.implication}")
    lines.append(f"aggregation: {system.aggregation}")
    lines.append(f"defuzzifier: {system.defuzzifier}")
    lines.append(f"resolution: {system.resolution}")
    lines.append(f"no_rule_fired: {_scalar(system.no_rule_fired)}")
    for key, variables in (("inputs", system.inputs), ("outputs", system.outputs)):
        lines.append(f"{key}:")
        for var in variables:
            lines += _variable_lines(var)
    lines.append("rules:")
    for r, rule in enumerate(system.rules):
        try:
            text = _scalar(format_rule(rule, system.inputs, system.outputs))
        except RuleBaseError as exc:
            raise RuleBaseError(f"rule {r + 1} (antecedent {list(rule.antecedent)}): {exc.detail}; YAML rules "
                                "need at least one condition", place=f"rules[{r}]") from None
        # a one-clause rule keeps the connective its text cannot show (MATLAB stores one per rule)
        one_clause_or = rule.connective == "or" and sum(1 for index in rule.antecedent if index) == 1
        if rule.weight == 1.0 and not one_clause_or:
            lines.append(f"  - {text}")
        else:
            lines.append(f"  - rule: {text}")
            if rule.weight != 1.0:
                lines.append(f"    weight: {_scalar(rule.weight)}")
            if one_clause_or:
                lines.append("    connective: or")
    if system.metadata:
        try:
            block = yaml.safe_dump({"metadata": system.metadata}, sort_keys=False, width=10**9)
        except yaml.YAMLError as exc:
            raise RuleBaseError(f"metadata holds a value YAML cannot write ({exc}); use plain numbers, "
                                "text, lists and mappings", place="metadata") from None
        lines += block.rstrip("\n").split("\n")
    lines.append(END)
    return "\n".join(lines) + "\n"

