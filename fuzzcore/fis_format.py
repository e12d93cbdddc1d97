"""MATLAB Fuzzy Logic Toolbox ``.fis`` files: a strict reader and a writer ``readfis`` accepts.

The format, as MATLAB's ``writefis`` writes it::

    [System]
    Name='tipper'
    Type='mamdani'                      # or 'sugeno'
    Version=2.0
    NumInputs=2
    NumOutputs=1
    NumRules=3
    AndMethod='min'                     # min | prod
    OrMethod='max'                      # max | probor
    ImpMethod='min'                     # min | prod
    AggMethod='max'                     # max | sum | probor
    DefuzzMethod='centroid'             # centroid | bisector | mom | som | lom | wtaver | wtsum

    [Input1]
    Name='service'
    Range=[0 10]
    NumMFs=3
    MF1='poor':'gaussmf',[1.5 0]        # 'name':'kind',[parameters in MATLAB's order]
    ...

    [Output1]
    ...

    [Rules]
    1 1, 1 (1) : 2                      # antecedent indices, consequent indices (weight) : connective

Rule lines hold one index per input, then one per output: ``k`` is the variable's k-th
membership function (1-based), ``-k`` its complement (NOT), ``0`` "don't care"; the weight is
in [0, 1]; the connective is 1 (AND) or 2 (OR). Rules bind to terms by index, never by name.

Reading accepts what real files contain: ``#`` and ``%`` comments (whole lines, or the end of a
line outside quotes), blank lines, Windows or old Mac line endings, a UTF-8 byte-order mark
(text that is not UTF-8 is read as Latin-1, as MATLAB on Windows may write it), numbers
written as ``1.000``, keys, section titles, kind and method names in any case, names in single
or double quotes with MATLAB's doubled-quote escape. ``NumInputs``, ``NumOutputs``,
``NumRules`` and ``NumMFs`` are optional; where present they must agree with what the file
lists. Keys missing from ``[System]`` take MATLAB's defaults (``Type='mamdani'``, ``min``,
``max``, ``min``, ``max``, ``centroid`` or, for Sugeno, ``wtaver``; the name defaults to the
file's stem). Anything else (an unknown key or section, a custom MATLAB function, a type-2
system, a hedge written as a fractional rule index) is refused. Every error is a
:class:`~fuzzcore.errors.RuleBaseError` naming the file and the line.

Names. fuzzcore's variables and terms need names usable in rule text
(:data:`fuzzcore.variables.NAME_PATTERN`). A ``.fis`` name that is not is renamed by
:func:`rule_text_name` (each run of other characters becomes ``_``; a leading ``_`` is added
before a digit, ``.`` or ``-``; a reserved word gets a trailing ``_``: ``'Food Quality'`` ->
``Food_Quality``, ``'1st'`` -> ``_1st``, ``'not'`` -> ``not_``) and a warning says so. Names
are the only thing reading can change: every number of a ``.fis`` file comes back unchanged
from ``.fis -> fuzzcore -> .fis`` (and through YAML), since numbers are written with
``repr``'s shortest exact form. Repeated term names in one variable are kept (rules use
indices); only YAML, which names terms uniquely, refuses them.

Writing refuses, with a :class:`~fuzzcore.errors.RuleBaseError`, what MATLAB would evaluate
differently: a ``resolution`` other than 101, a ``no_rule_fired`` policy other than
``midpoint``, the ``centroid_exact`` defuzzifier, a system name with a line break. The
system's ``description`` and ``metadata``, which the format has no place for, are written as
YAML (ASCII, other characters escaped) in consecutive comment lines starting ``%fuzzcore:``
before ``[System]`` (MATLAB and Octave skip them) and read back, so a saved system loads back
equal.
"""
from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from . import yaml_format
from .compiled import (AGGREGATIONS, AND_METHODS, IMPLICATIONS, MAMDANI_DEFUZZIFIERS,
                       OR_METHODS, SUGENO_DEFUZZIFIERS, SYSTEMS)
from .errors import RuleBaseError
from .membership import KINDS, check_params
from .rules import Rule
from .system import FuzzySystem
from .variables import NAME_PATTERN, RESERVED, Term, Variable

#: the output grid of MATLAB's Mamdani defuzzification (evalfis' default; a .fis cannot say otherwise)
MATLAB_RESOLUTION = 101
#: prefix of the comment lines that carry ``description`` and ``metadata`` (YAML)
EXTRA_PREFIX = "%fuzzcore:"

#: defuzzifiers MATLAB knows, by system type (``centroid_exact`` is fuzzcore's own)
_DEFUZZIFIERS = {
    "mamdani": tuple(k for k in MAMDANI_DEFUZZIFIERS if k != "centroid_exact"),
    "sugeno": tuple(SUGENO_DEFUZZIFIERS),
}
#: [System] method key (lower case) -> (FuzzySystem field, MATLAB's names for it)
_METHODS = {
    "andmethod": ("and_method", tuple(AND_METHODS)),
    "ormethod": ("or_method", tuple(OR_METHODS)),
    "impmethod": ("implication", tuple(IMPLICATIONS)),
    "aggmethod": ("aggregation", tuple(AGGREGATIONS)),
}
_SYSTEM_KEYS = ("Name", "Type", "Version", "NumInputs", "NumOutputs", "NumRules", "AndMethod",
                "OrMethod", "ImpMethod", "AggMethod", "DefuzzMethod")
_VARIABLE_KEYS = ("Name", "Range", "NumMFs", "MF1, MF2, ...")

_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_QUOTED = r"'(?:[^']|'')*'|\"(?:[^\"]|\"\")*\""
_STRING = re.compile(_QUOTED)
_SECTION = re.compile(r"\[\s*([A-Za-z]+)\s*(\d*)\s*\]")
_KEY = re.compile(r"([A-Za-z][A-Za-z0-9]*)\s*=\s*(.*)")
_MF_KEY = re.compile(r"MF(\d+)", re.IGNORECASE)
_MF_VALUE = re.compile(rf"({_QUOTED})\s*:\s*({_QUOTED})\s*,\s*\[([^\[\]]*)\]")
_RULE = re.compile(r"([^,():]*),([^,():]*)\(([^()]*)\)\s*:\s*([^,():]*)")
_RULE_FORM = "'a1 ... an, c1 ... cm (weight) : connective', e.g. '1 -2, 3 (1) : 1'"
_OTHER_CHARACTERS = re.compile(r"[^A-Za-z0-9_.\-]+")


def rule_text_name(name: str) -> str:
    """The rule-text-usable name fuzzcore gives a ``.fis`` variable or term name.

    A usable name (see :data:`fuzzcore.variables.NAME_PATTERN`) comes back unchanged.
    Otherwise each run of characters other than ASCII letters, digits, ``_``, ``.`` and
    ``-`` becomes ``_``; a name then starting with a digit, ``.`` or ``-`` gets a leading
    ``_``; a reserved word of the rule language gets a trailing ``_``.
    """
    if NAME_PATTERN.fullmatch(name) and name not in RESERVED:
        return name
    text = _OTHER_CHARACTERS.sub("_", name)
    if not re.match(r"[A-Za-z_]", text):
        text = "_" + text
    return text + "_" if text in RESERVED else text


def _number_text(value: float) -> str:
    """The shortest text that reads back as exactly ``value`` (``repr``), ``1.0`` written ``1``."""
    text = repr(float(value))
    return text[:-2] if text.endswith(".0") else text


# --------------------------------------------------------------------------- reading
@dataclass
class _Section:
    title: str                       # "system", "input", "output" or "rules" (lower case)
    number: int | None               # N of [InputN] / [OutputN]
    line: int                        # line of the [title] header
    body: list[tuple[int, str]] = field(default_factory=list)   # (line, comment-free text)

    @property
    def label(self) -> str:
        return f"[{self.title.capitalize()}{self.number or ''}]"


def _strip_comment(raw: str) -> str:
    """``raw`` without a ``#`` / ``%`` comment (outside quotes) and surrounding white space."""
    quote = None
    for i, ch in enumerate(raw):
        if quote:
            if ch == quote:
                quote = None
        elif ch in "'\"":
            quote = ch
        elif ch in "%#":
            return raw[:i].strip()
    return raw.strip()


def _decode(data: bytes) -> str:
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")


class _Reader:
    def __init__(self, text: str, source: str | None):
        self.source = source
        self.lines = re.split(r"\r\n|\r|\n", text)
        if len(self.lines) > 1 and not self.lines[-1]:
            self.lines.pop()  # the final line end ends the last line; it does not start another

    def error(self, message: str, line: int) -> RuleBaseError:
        return RuleBaseError(message, source=self.source, place=f"line {line}")

    # ---------------------------------------------------------------- tokens
    def string(self, value: str, line: int, what: str) -> str:
        if not _STRING.fullmatch(value):
            raise self.error(f"{what} {value!r}: expected a quoted string, e.g. 'text'", line)
        quote = value[0]
        return value[1:-1].replace(quote * 2, quote)

    def number(self, text: str, line: int, what: str) -> float:
        if not _NUMBER.fullmatch(text):
            raise self.error(f"{what} {text!r} is not a number", line)
        value = float(text)
        if not math.isfinite(value):
            raise self.error(f"{what} {text!r} is not a finite number", line)
        return value

    def integer(self, text: str, line: int, what: str) -> int:
        value = self.number(text, line, what)
        if value != int(value):
            raise self.error(f"{what} {text!r} is not an integer", line)
        return int(value)

    def numbers(self, text: str, line: int, what: str) -> list[float]:
        return [self.number(t, line, what) for t in re.split(r"[\s,]+", text.strip()) if t]

    def bracketed(self, value: str, line: int, what: str) -> list[float]:
        if not (value.startswith("[") and value.endswith("]")):
            raise self.error(f"{what} {value!r}: expected numbers in brackets, e.g. [0 1]", line)
        return self.numbers(value[1:-1], line, f"{what} entry")

    def name(self, value: str, line: int, what: str) -> str:
        name = self.string(value, line, f"{what} name")
        if not name:
            raise self.error(f"{what} name is empty; expected a name", line)
        usable = rule_text_name(name)
        if usable != name:
            warnings.warn(f"{self.source or '<.fis text>'}: line {line}: {what} name {name!r} is not usable "
                          f"in rule text; renamed {usable!r}", stacklevel=2)
        return usable

    # ---------------------------------------------------------------- structure
    def sections(self) -> list[_Section]:
        sections: list[_Section] = []
        for n, raw in enumerate(self.lines, start=1):
            text = _strip_comment(raw)
            if not text:
                continue
            header = _SECTION.fullmatch(text)
            if header:
                title, number = header.group(1).lower(), header.group(2)
                numbered = title in ("input", "output")
                if title not in ("system", "input", "output", "rules") or numbered != bool(number):
                    raise self.error(f"unknown section {text}; expected [System], [Input1], [Input2], ..., "
                                     "[Output1], ... or [Rules]", n)
                sections.append(_Section(title, int(number) if numbered else None, n))
            elif not sections:
                raise self.error(f"{text!r} comes before any section; a .fis file starts with [System]", n)
            else:
                sections[-1].body.append((n, text))
        return sections

    def one(self, sections: list[_Section], title: str, missing_line: int) -> _Section:
        found = [s for s in sections if s.title == title]
        if not found:
            raise self.error(f"the [{title.capitalize()}] section is missing", missing_line)
        if len(found) > 1:
            raise self.error(f"a second [{title.capitalize()}] section (the first is at line {found[0].line})",
                             found[1].line)
        return found[0]

    def numbered(self, sections: list[_Section], title: str, count: tuple[int, int] | None) -> list[_Section]:
        found = [s for s in sections if s.title == title]
        seen: dict[int, _Section] = {}
        for s in found:
            if s.number in seen:
                raise self.error(f"a second {s.label} section (the first is at line {seen[s.number].line})", s.line)
            seen[s.number] = s
        for k in range(1, len(found) + 1):
            if k not in seen:
                last = seen[max(seen)]
                raise self.error(f"{last.label} but no [{title.capitalize()}{k}]; sections are numbered "
                                 "1, 2, ... without gaps", last.line)
        if count is not None and count[0] != len(found):
            key = "NumInputs" if title == "input" else "NumOutputs"
            raise self.error(f"{key}={count[0]} but the file has {len(found)} [{title.capitalize()}N] "
                             "section(s)", count[1])
        return [seen[k] for k in range(1, len(found) + 1)]

    def keys(self, section: _Section, allowed: tuple[str, ...]) -> dict[str, tuple[str, int, str]]:
        """``key.lower() -> (value, line, key as written)`` of a section of ``Key=value`` lines."""
        out: dict[str, tuple[str, int, str]] = {}
        for n, text in section.body:
            key, value = self.key_value(text, n, section)
            low = key.lower()
            if low not in {k.lower() for k in allowed}:
                raise self.error(f"unknown key {key!r} in {section.label}; expected {', '.join(allowed)}", n)
            if low in out:
                raise self.error(f"{key} is given twice in {section.label} (first at line {out[low][1]})", n)
            out[low] = (value, n, key)
        return out

    def key_value(self, text: str, line: int, section: _Section) -> tuple[str, str]:
        match = _KEY.fullmatch(text)
        if not match:
            raise self.error(f"{text!r}: expected Key=value in {section.label}", line)
        return match.group(1), match.group(2).strip()

    # ---------------------------------------------------------------- parts
    def system_settings(self, section: _Section) -> tuple[dict[str, Any], dict[str, tuple[int, int]]]:
        keys = self.keys(section, _SYSTEM_KEYS)
        settings: dict[str, Any] = {}
        if "name" in keys:
            value, line, _ = keys["name"]
            settings["name"] = self.string(value, line, "Name")
        else:
            settings["name"] = Path(self.source).stem if self.source else "fuzzy-system"
        system_type = "mamdani"
        if "type" in keys:
            value, line, _ = keys["type"]
            system_type = self.choice(self.string(value, line, "Type"), tuple(SYSTEMS), "Type", line)
        settings["type"] = system_type
        if "version" in keys:
            value, line, _ = keys["version"]
            self.number(value, line, "Version")
        for key, (attr, choices) in _METHODS.items():
            if key in keys:
                value, line, written = keys[key]
                settings[attr] = self.choice(self.string(value, line, written), choices, written, line)
        settings["defuzzifier"] = "wtaver" if system_type == "sugeno" else "centroid"
        if "defuzzmethod" in keys:
            value, line, written = keys["defuzzmethod"]
            settings["defuzzifier"] = self.choice(self.string(value, line, written), _DEFUZZIFIERS[system_type],
                                                  f"{written} (for a {system_type} system)", line)
        counts = {}
        for key in ("numinputs", "numoutputs", "numrules"):
            if key in keys:
                value, line, written = keys[key]
                count = self.integer(value, line, written)
                if count < 0:
                    raise self.error(f"{written}={value} is negative", line)
                counts[key] = (count, line)
        return settings, counts

    def choice(self, value: str, choices: tuple[str, ...], what: str, line: int) -> str:
        low = value.lower()
        if low not in choices:
            raise self.error(f"{what} {value!r}: expected one of {', '.join(choices)} (custom MATLAB functions "
                             "and type-2 systems are not supported)", line)
        return low

    def variable(self, section: _Section, n_inputs: int, system_type: str) -> tuple[Variable, int]:
        """The variable of an [InputN]/[OutputN] section and the line of its name."""
        is_input = section.title == "input"
        what = f"{section.title} {section.number}"
        name = lo_hi = n_mfs = None
        terms: list[Term] = []
        for n, text in section.body:
            key, value = self.key_value(text, n, section)
            low = key.lower()
            mf = _MF_KEY.fullmatch(key)
            if mf:
                if int(mf.group(1)) != len(terms) + 1:
                    raise self.error(f"{key} in {section.label}: expected MF{len(terms) + 1} (membership "
                                     "functions are numbered 1, 2, ... in order)", n)
                terms.append(self.term(value, n, is_input, n_inputs, system_type, f"{what} MF{len(terms) + 1}"))
            elif low in ("name", "range", "nummfs"):
                seen = {"name": name, "range": lo_hi, "nummfs": n_mfs}[low]
                if seen is not None:
                    raise self.error(f"{key} is given twice in {section.label} (first at line {seen[1]})", n)
                if low == "name":
                    name = (self.name(value, n, what), n)
                elif low == "range":
                    bounds = self.bracketed(value, n, "Range")
                    if len(bounds) != 2:
                        raise self.error(f"Range {value}: expected [lo hi], two numbers", n)
                    lo_hi = (tuple(bounds), n)
                else:
                    n_mfs = (self.integer(value, n, key), n)
            else:
                raise self.error(f"unknown key {key!r} in {section.label}; expected {', '.join(_VARIABLE_KEYS)}", n)
        for missing, value in (("Name", name), ("Range", lo_hi)):
            if value is None:
                raise self.error(f"{section.label} has no {missing}", section.line)
        if n_mfs is not None and n_mfs[0] != len(terms):
            raise self.error(f"NumMFs={n_mfs[0]} but {section.label} lists {len(terms)} membership function(s)",
                             n_mfs[1])
        try:
            variable = Variable(name[0], lo_hi[0], tuple(terms))
        except RuleBaseError as exc:
            raise self.error(exc.detail, lo_hi[1]) from None
        if not is_input and not terms:
            raise self.error(f"output {variable.name!r} has no membership functions; expected at least one",
                             n_mfs[1] if n_mfs else section.line)
        return variable, name[1]

    def term(self, value: str, line: int, is_input: bool, n_inputs: int, system_type: str, what: str) -> Term:
        match = _MF_VALUE.fullmatch(value)
        if not match:
            raise self.error(f"{what} {value!r}: expected 'name':'kind',[parameters], e.g. 'low':'trimf',[0 0 1]",
                             line)
        name = self.name(match.group(1), line, what)
        kind_name = self.string(match.group(2), line, "kind").lower()
        if kind_name not in KINDS:
            raise self.error(f"{what}: unknown membership function {kind_name!r}; expected one of "
                             f"{', '.join(KINDS)}", line)
        kind = KINDS[kind_name]
        if kind.output_only and (is_input or system_type == "mamdani"):
            where = "an input" if is_input else "a Mamdani output"
            raise self.error(f"{what}: {kind.name} is a Sugeno output kind, not usable on {where}", line)
        if system_type == "sugeno" and not is_input and not kind.output_only:
            raise self.error(f"{what}: {kind.name}: a Sugeno output must be 'constant' or 'linear'", line)
        params = self.numbers(match.group(3), line, f"{what} parameter")
        problem = check_params(kind, params, n_inputs)
        if problem:
            raise self.error(f"{what} ({kind.name} {match.group(3).strip()!r}): {problem}", line)
        return Term(name, kind.name, params)

    def rule(self, text: str, line: int, inputs: tuple[Variable, ...], outputs: tuple[Variable, ...],
             sugeno: bool) -> Rule:
        match = _RULE.fullmatch(text)
        if not match:
            raise self.error(f"rule {text!r}: expected {_RULE_FORM}", line)
        ante_text, cons_text, weight_text, conn_text = (g.strip() for g in match.groups())
        parts = []
        for part, variables, kind in ((ante_text, inputs, "input"), (cons_text, outputs, "output")):
            tokens = part.split()
            if len(tokens) != len(variables):
                raise self.error(f"rule {text!r}: {len(tokens)} {kind} index(es), expected {len(variables)} "
                                 f"(one per {kind}: {', '.join(v.name for v in variables)})", line)
            parts.append(tuple(self.integer(t, line, f"rule {kind} index") for t in tokens))
        weight = self.number(weight_text, line, "rule weight")
        connective = self.integer(conn_text, line, "rule connective")
        if connective not in (1, 2):
            raise self.error(f"rule connective {conn_text!r}: expected 1 (AND) or 2 (OR)", line)
        try:
            rule = Rule(parts[0], parts[1], weight, "and" if connective == 1 else "or")
            rule.check(inputs, outputs)
        except RuleBaseError as exc:
            raise self.error(f"rule {text!r}: {exc.detail}", line) from None
        if sugeno and any(c < 0 for c in rule.consequent):
            raise self.error(f"rule {text!r}: a Sugeno rule cannot negate its output term", line)
        return rule

    def extra(self) -> dict[str, Any]:
        """``description`` and ``metadata`` from the ``%fuzzcore:`` comment lines (YAML)."""
        block = [(n, raw[len(EXTRA_PREFIX):]) for n, raw in enumerate(self.lines, start=1)
                 if raw.startswith(EXTRA_PREFIX)]
        if not block:
            return {}
        first = block[0][0]
        for (previous, _), (n, _) in zip(block, block[1:]):
            if n != previous + 1:
                raise self.error(f"the {EXTRA_PREFIX} lines must follow one another; line {previous + 1} "
                                 "breaks them", previous + 1)
        # padded so that YAML's line numbers are the file's
        text = "\n" * (first - 1) + "\n".join(t[1:] if t.startswith(" ") else t for _, t in block)
        try:
            data = yaml_format.load_data(text, self.source)
        except RuleBaseError as exc:
            raise RuleBaseError(f"in the {EXTRA_PREFIX} lines: {exc.detail}", source=self.source,
                                place=exc.place or f"line {first}") from None
        if not isinstance(data, dict) or not set(data) <= {"description", "metadata"}:
            raise self.error(f"the {EXTRA_PREFIX} lines must hold a mapping with 'description' and/or "
                             "'metadata'", first)
        if not isinstance(data.get("description", ""), str):
            raise self.error(f"{EXTRA_PREFIX} description must be text", first)
        if not isinstance(data.get("metadata", {}), dict):
            raise self.error(f"{EXTRA_PREFIX} metadata must be a mapping", first)
        return data

    # ---------------------------------------------------------------- whole file
    def system(self) -> FuzzySystem:
        sections = self.sections()
        system_section = self.one(sections, "system", 1)
        settings, counts = self.system_settings(system_section)
        input_sections = self.numbered(sections, "input", counts.get("numinputs"))
        output_sections = self.numbered(sections, "output", counts.get("numoutputs"))
        rules_section = self.one(sections, "rules", len(self.lines))
        for sections_, kind in ((input_sections, "input"), (output_sections, "output")):
            if not sections_:
                raise self.error(f"no [{kind.capitalize()}1] section; a system needs at least one {kind}",
                                 system_section.line)
        system_type = settings["type"]
        n_in = len(input_sections)
        built, name_lines = [], {}
        for section in input_sections + output_sections:
            variable, line = self.variable(section, n_in, system_type)
            if variable.name in name_lines:
                raise self.error(f"variable name {variable.name!r} is already used (line {name_lines[variable.name]})"
                                 "; variable names must be unique", line)
            name_lines[variable.name] = line
            built.append(variable)
        inputs, outputs = tuple(built[:n_in]), tuple(built[n_in:])
        rules = tuple(self.rule(text, n, inputs, outputs, system_type == "sugeno")
                      for n, text in rules_section.body)
        if "numrules" in counts and counts["numrules"][0] != len(rules):
            count, line = counts["numrules"]
            raise self.error(f"NumRules={count} but [Rules] lists {len(rules)} rule(s)", line)
        if not rules:
            raise self.error("[Rules] lists no rule; expected at least one", rules_section.line)
        settings.update(self.extra())
        try:
            return FuzzySystem(inputs=inputs, outputs=outputs, rules=rules, **settings)
        except RuleBaseError as exc:  # every check above should have caught it first
            raise self.error(f"{exc.place}: {exc.detail}" if exc.place else exc.detail,
                             system_section.line) from None


def loads(text: str, source: str | None = None) -> FuzzySystem:
    """Read a fuzzy system from the text of a ``.fis`` file; ``source`` names it in errors."""
    return _Reader(text, source).system()


def read(path: str | Path) -> FuzzySystem:
    """Read a MATLAB ``.fis`` file."""
    path = Path(path)
    return loads(_decode(path.read_bytes()), source=str(path))


# --------------------------------------------------------------------------- writing
def _check_writable(system: FuzzySystem) -> None:
    problems = []
    if system.resolution != MATLAB_RESOLUTION:
        problems.append((f"resolution {system.resolution}: MATLAB's evalfis defuzzifies on "
                         f"{MATLAB_RESOLUTION} points and a .fis file cannot say otherwise", "resolution"))
    if system.no_rule_fired != "midpoint":
        problems.append((f"no_rule_fired {system.no_rule_fired!r}: MATLAB returns the midpoint of the "
                         "output range when no rule fires", "no_rule_fired"))
    if system.defuzzifier not in _DEFUZZIFIERS[system.type]:
        problems.append((f"defuzzifier {system.defuzzifier!r} is fuzzcore's own; MATLAB has "
                         f"{', '.join(_DEFUZZIFIERS[system.type])}", "defuzzifier"))
    if "\n" in system.name or "\r" in system.name:
        problems.append((f"name {system.name!r} has a line break; a .fis name is one line", "name"))
    if problems:
        message, place = problems[0]
        raise RuleBaseError(f"cannot be written as a MATLAB .fis file: {message}", place=place)


def _quote(text: str) -> str:
    return "'" + text.replace("'", "''") + "'"


def _variable_lines(title: str, var: Variable) -> list[str]:
    lines = ["", title, f"Name={_quote(var.name)}",
             f"Range=[{_number_text(var.range[0])} {_number_text(var.range[1])}]", f"NumMFs={len(var.terms)}"]
    for k, term in enumerate(var.terms, start=1):
        params = " ".join(_number_text(p) for p in term.params)
        lines.append(f"MF{k}={_quote(term.name)}:{_quote(term.kind)},[{params}]")
    return lines


def dumps(system: FuzzySystem) -> str:
    """The ``.fis`` text of ``system``, as MATLAB's ``writefis`` lays it out; :func:`loads` reads it back equal.

    Raises :class:`~fuzzcore.errors.RuleBaseError` for what MATLAB would evaluate differently
    (see the module docstring).
    """
    _check_writable(system)
    lines = []
    extra = {key: value for key, value in (("description", system.description), ("metadata", system.metadata))
             if value}
    if extra:
        try:
            # ASCII: other characters are escaped (PyYAML writes some line breaks, e.g. U+0085, raw otherwise)
            block = yaml.safe_dump(extra, sort_keys=False, width=10**9, allow_unicode=False)
        except yaml.YAMLError as exc:
            raise RuleBaseError(f"metadata holds a value YAML cannot write ({exc})", place="metadata") from None
        lines += [f"{EXTRA_PREFIX} {line}" if line else EXTRA_PREFIX for line in block.split("\n")[:-1]]
    lines += [
        "[System]",
        f"Name={_quote(system.name)}",
        f"Type={_quote(system.type)}",
        "Version=2.0",
        f"NumInputs={len(system.inputs)}",
        f"NumOutputs={len(system.outputs)}",
        f"NumRules={len(system.rules)}",
        f"AndMethod={_quote(system.and_method)}",
        f"OrMethod={_quote(system.or_method)}",
        f"ImpMethod={_quote(system.implication)}",
        f"AggMethod={_quote(system.aggregation)}",
        f"DefuzzMethod={_quote(system.defuzzifier)}",
    ]
    for i, var in enumerate(system.inputs, start=1):
        lines += _variable_lines(f"[Input{i}]", var)
    for o, var in enumerate(system.outputs, start=1):
        lines += _variable_lines(f"[Output{o}]", var)
    lines += ["", "[Rules]"]
    for rule in system.rules:
        lines.append(f"{' '.join(map(str, rule.antecedent))}, {' '.join(map(str, rule.consequent))} "
                     f"({_number_text(rule.weight)}) : {1 if rule.connective == 'and' else 2}")
    return "\n".join(lines) + "\n"

