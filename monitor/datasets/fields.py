"""JSON files read with errors that name the file, and typed access to their objects whose
errors name the file and the field path.

Used by the readers of on-disk formats (:mod:`monitor.datasets.scene_folder`,
:mod:`monitor.datasets.nuscenes`): :func:`load_json` reads a file, and
``fields.number("yaw")`` returns a float or raises
``ValueError("scene.json: frames[3].annotations[2].yaw: 'x' is not a finite number")``.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np


def load_json(path: Path, what: str):
    """The JSON value in the file ``path`` (UTF-8); ``what`` names the file in messages.

    Raises
    ------
    FileNotFoundError
        ``path`` is not a file.
    ValueError
        Naming the file: not valid JSON, not UTF-8, or nested too deeply to read.
    """
    if not path.is_file():
        raise FileNotFoundError(f"{what} {path} does not exist")
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not valid JSON ({exc})") from exc
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not UTF-8 text (byte {exc.start}: {exc.reason})") from None
    except RecursionError:
        raise ValueError(f"{path}: JSON nested too deeply to read") from None


def _finite(value) -> bool:
    """A JSON number (not a bool) that is finite as a float (an integer beyond float's
    range is not)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


class JsonFields:
    """Typed access to one JSON object; errors name the file and the field path."""

    def __init__(self, obj, where: str, file: Path):
        if not isinstance(obj, dict):
            raise ValueError(f"{file}: {where} is a {type(obj).__name__}, expected an object")
        self.obj, self.where, self.file = obj, where, file

    def error(self, key: str, message: str) -> ValueError:
        return ValueError(f"{self.file}: {self.where}.{key}: {message}")

    def get(self, key: str):
        if key not in self.obj:
            raise ValueError(f"{self.file}: {self.where}: field {key!r} is missing")
        return self.obj[key]

    def number(self, key: str) -> float:
        value = self.get(key)
        if not _finite(value):
            raise self.error(key, f"{value!r} is not a finite number")
        return float(value)

    def integer(self, key: str, *, optional: bool = False) -> int | None:
        value = self.get(key)
        if value is None and optional:
            return None
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"{value!r} is not an integer")
        return value

    def string(self, key: str, *, optional: bool = False) -> str | None:
        value = self.get(key)
        if value is None and optional:
            return None
        if not isinstance(value, str):
            raise self.error(key, f"{value!r} is not a string")
        return value

    def numbers(self, key: str, n: int) -> list[float]:
        value = self.get(key)
        if (not isinstance(value, list) or len(value) != n
                or not all(_finite(v) for v in value)):
            raise self.error(key, f"{value!r} is not a list of {n} finite numbers")
        return [float(v) for v in value]

    def matrix(self, key: str, rows: int, cols: int) -> np.ndarray:
        value = self.get(key)
        ok = isinstance(value, list) and len(value) == rows and all(
            isinstance(r, list) and len(r) == cols
            and all(_finite(v) for v in r)
            for r in value)
        if not ok:
            raise self.error(key, f"expected a {rows}x{cols} list of lists of finite numbers")
        return np.array(value, dtype=np.float64)

    def objects(self, key: str) -> list["JsonFields"]:
        value = self.get(key)
        if not isinstance(value, list):
            raise self.error(key, f"is a {type(value).__name__}, expected a list")
        return [JsonFields(v, f"{self.where}.{key}[{i}]", self.file) for i, v in enumerate(value)]
