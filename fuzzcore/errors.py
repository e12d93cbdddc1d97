"""The one error type of fuzzcore's readers and validators."""
from __future__ import annotations


class RuleBaseError(ValueError):
    """A rule base (YAML or MATLAB .fis, or one built in code) is invalid.

    The message names where: the file (when there is one), the place inside it (a YAML
    path such as ``inputs.iou.terms.low`` or a ``.fis`` line number) and what was expected.
    """

    def __init__(self, message: str, *, source: str | None = None, place: str | None = None):
        self.source = source
        self.place = place
        self.detail = message
        prefix = ": ".join(p for p in (source, place) if p)
        super().__init__(f"{prefix}: {message}" if prefix else message)
