"""Where the shipped rule bases live: ``rules/`` of the checkout, or the installed copy.

A wheel installs ``rules/`` as the data package ``monitor.rules``; an editable install or a
source checkout reads ``rules/`` in place (so edits there take effect at once).
"""
from __future__ import annotations

import importlib.resources
from pathlib import Path

_CHECKOUT_RULES = Path(__file__).resolve().parents[1] / "rules"

#: the paper's knowledge-based rule base
DEFAULT_RULES = "fuzzrisk.yaml"


def rules_dir() -> Path:
    """The folder holding the shipped rule bases."""
    if _CHECKOUT_RULES.is_dir():
        return _CHECKOUT_RULES
    return Path(str(importlib.resources.files("monitor.rules")))


def shipped_rules(name: str = DEFAULT_RULES) -> Path:
    """Path of a shipped rule base; ``FileNotFoundError`` lists the ones there are."""
    path = rules_dir() / name
    if not path.is_file():
        names = ", ".join(sorted(p.name for p in rules_dir().glob("*.yaml")))
        raise FileNotFoundError(f"no shipped rule base {name!r}; shipped: {names}")
    return path
