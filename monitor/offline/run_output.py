"""The output folder of ``fuzzrisk monitor``: per-frame JSON lines, timelines, a summary; resumable.

Layout::

    OUT/run.json               what the run is (sources, rule base and prior digests,
                               configuration, scenes): a later run into OUT must match it
    OUT/scenes/<scene>.jsonl   one report per frame, in order (:func:`report_row`)
    OUT/scenes/<scene>.png     the scene's risk timeline, written when the scene is complete
    OUT/summary.md             per-scene table, frames that could not be processed, timelines

Lines are appended as frames finish and flushed to disk (``fsync``) after each batch, so an
interrupted run leaves complete lines (and at most one torn last line). Started again with
the same ``run.json``, :class:`RunOutput` checks every existing line (valid JSON, the scene's
frames in order, shield decisions that replay to the same values), drops a torn last line
and hands back only the frames still to do. A folder holding another run, or files that are
not a run, is never written into without ``overwrite``; then only the run's own files
(``run.json``, ``summary.md``, ``scenes/*.jsonl``, ``scenes/*.png``) are removed. The PNG and
Markdown files are written whole or not at all (temporary file, then a rename).

The shield runs here, over each scene's frames in order (it and what it compares from frame
to frame are the only parts with state), given each frame's risk, time, the ego's speed, the
report's unseen objects and what of them came out of the road since the frame before
(:func:`monitor.risk_monitor.unseen_emerged`, stored as ``emerged``; for a shield that
confirms it); a resume replays it from the stored rows' ``risk``, ``time``, ``ego_speed``,
``unseen``, ``unseen_contact``, ``emerged`` and ``walkers`` (the detector's walkers, for a
shield that watches them). A frame that could not be processed has status ``unprocessed``,
its ``error``, no risk and no shield decision (the shield keeps its state across it; the
next frame has no frames before it to be compared with, as the first frame after a resume).
"""
from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fuzzcore.outputs import write_text
from monitor.config import ShieldConfig
from monitor.offline.run import Chunk, FrameResult, ScenePlan
from monitor.report.figures import save_risk_timeline
from monitor.report.tables import format_table
from monitor.depth.geometric import GeometricRetriever
from monitor.risk_monitor import STATUSES, shift_earlier, unseen_emerged
from monitor.shield import Shield

RUN_FILE = "run.json"
SUMMARY_FILE = "summary.md"
SCENES_DIR = "scenes"
#: status of a frame that could not be processed
UNPROCESSED = "unprocessed"
_UNSAFE = re.compile(r"[^A-Za-z0-9._-]")


def scene_file_stem(name: str) -> str:
    """The file name of a scene's outputs: its name with anything but ``A-Za-z0-9._-`` as ``_``."""
    return _UNSAFE.sub("_", name) or "_"


def _number(x: float) -> float | None:
    return None if x is None or not math.isfinite(x) else float(x)


def report_row(result: FrameResult, engaged: bool | None, deceleration: float | None,
               emerged: np.ndarray | None) -> dict:
    """The JSON line of one frame.

    Fields: ``scene``, ``frame`` (index), ``key`` (file stem), ``token`` (nuScenes sample or
    null), ``time`` (s), ``ego_speed`` (m/s), then the monitor's report (``risk``, ``status``,
    ``reason``, ``iou``, ``rdd``, ``S``, ``P``, ``matched``, ``fired``, ``free_distance``,
    ``unseen``, ``unseen_contact``, ``timings_ms``: see
    :meth:`monitor.risk_monitor.RiskReport.to_dict`), ``alignment`` (``matching``, then per S:
    ``partner`` row of P or -1, ``iou`` (its coverage under coverage matching), ``rdd``,
    ``counted``; ``objects``, then per detection ``det_iou``, ``det_rdd``, ``det_counted``,
    empty with ``objects`` "depth"; see :class:`monitor.alignment.Alignment`), ``target``
    (1 - USC~; null without ground truth or none in range), ``emerged`` (per unseen object,
    the share of it that came out of the road since the frame before, null where not known;
    null without a view, and in every frame of a run whose shield does not confirm what came
    out of the road: ``emerged``), ``walkers`` (``[x, y]`` per walker the detector reports,
    ego frame, metres: :attr:`FrameResult.walkers`) and ``shield`` (``engaged``,
    ``deceleration`` m/s^2).
    An unprocessed frame has ``status`` "unprocessed", ``error``, and null ``risk`` and ``shield``.
    """
    row = {"scene": result.scene, "frame": result.index, "key": result.key, "token": result.token,
           "time": result.timestamp, "ego_speed": result.ego_speed}
    ob = result.observation
    if ob is None:
        return {**row, "risk": None, "status": UNPROCESSED, "error": result.error, "target": None,
                "shield": None}
    report = ob.report
    a = report.alignment
    alignment = None if a is None else {"matching": a.matching, "partner": a.partner.tolist(),
                                        "iou": a.pair_iou.tolist(), "rdd": a.pair_rdd.tolist(),
                                        "counted": a.matched.tolist(), "objects": a.objects,
                                        "det_iou": a.det_iou.tolist(), "det_rdd": a.det_rdd.tolist(),
                                        "det_counted": a.det_counted.tolist()}
    target = _number(ob.target) if result.has_ground_truth else None
    stored = None if emerged is None else [_number(e) for e in emerged.tolist()]
    return {**row, **report.to_dict(), "alignment": alignment, "target": target, "emerged": stored,
            "walkers": result.walkers.tolist(), "shield": {"engaged": engaged, "deceleration": deceleration}}


#: what a resume reads from a processed frame's line besides ``ego_speed``: what the shield
#: replays from and the decision it must give again
_REPLAYED = ("risk", "unseen", "unseen_contact", "emerged", "walkers", "shield")


def _stored_rows(value, columns: int):
    """A line's ``unseen`` (``columns`` 3) or ``walkers`` (2) as the shield takes it: None,
    or (k, columns) rows (an empty list read back from JSON has lost its shape)."""
    return np.empty((0, columns)) if isinstance(value, list) and not value else value


def _stored_shares(value):
    """A line's ``emerged`` or ``unseen_contact`` as the shield takes it: None, or (k,)
    shares with NaN for null."""
    return None if value is None else np.array([np.nan if e is None else e for e in value], dtype=np.float64)


def _digest_json(data) -> str:
    return json.dumps(data, sort_keys=True)


@dataclass
class _Scene:
    """One scene's file, shield and series (for the timeline and the summary)."""

    plan: ScenePlan
    path: Path
    shield: Shield
    keys: list[str]
    done: int = 0
    time: list = field(default_factory=list)
    risk: list = field(default_factory=list)
    target: list = field(default_factory=list)
    status: list = field(default_factory=list)
    engaged: list = field(default_factory=list)
    errors: list = field(default_factory=list)
    handle: object = None
    earlier: list = field(default_factory=list)  # the last frames' reports, with the ego's travel since

    @property
    def complete(self) -> bool:
        return self.done == self.plan.n_frames

    def take(self, row: dict) -> None:
        self.time.append(row["time"])
        self.risk.append(np.nan if row["risk"] is None else row["risk"])
        self.target.append(np.nan if row["target"] is None else row["target"])
        self.status.append(row["status"])
        if row["status"] == UNPROCESSED:
            self.errors.append((row["frame"], row["key"], row["error"]))
        else:
            self.engaged.append(row["shield"]["engaged"])
        self.done += 1


class RunOutput:
    """The output folder of one run (layout and resume rules in the module docstring).

    Parameters
    ----------
    out : str or Path
    description : dict
        What the run is (JSON-ready); stored as ``run.json`` and compared on a resume.
    plans : list of ScenePlan
    shield : ShieldConfig
    overwrite : bool
        Start afresh even when ``out`` holds a run (its files are removed first).
    retriever : GeometricRetriever, optional
        The run's geometric view (its camera and configuration), for the unseen objects'
        emerged shares when the shield confirms what came out of the road (the monitors'
        views then keep their blocks). None for the paper's view: the shares are NaN (not
        measured). A shield that does not confirm it gets none (``emerged`` null).

    Raises
    ------
    FileExistsError
        ``out`` holds another run or files that are not a run, without ``overwrite``.
    ValueError
        An existing line that does not belong where it is (the message names the file
        and line and says to pass ``overwrite``).
    """

    def __init__(self, out: str | Path, description: dict, plans: list[ScenePlan], shield: ShieldConfig,
                 *, overwrite: bool = False, retriever: GeometricRetriever | None = None):
        self.out = Path(out)
        self.retriever = retriever
        self.measure_emerged = shield.confirm_emerged is not None
        self.threshold = shield.threshold
        stems = {}
        for plan in plans:
            stem = scene_file_stem(plan.name)
            if stem in stems:
                raise ValueError(f"scenes {stems[stem]!r} and {plan.name!r} have the same output file name "
                                 f"{stem!r}; run them apart")
            stems[stem] = plan.name
        description = json.loads(json.dumps(description))  # as it reads back
        run_path = self.out / RUN_FILE
        if self.out.exists() and not self.out.is_dir():
            raise FileExistsError(f"output {self.out} exists and is not a folder")
        if overwrite:
            self._remove_own_files()
        elif run_path.is_file():
            try:
                stored = json.loads(run_path.read_text(encoding="utf-8"))
            except json.JSONDecodeError as exc:
                raise ValueError(f"{run_path}: not valid JSON ({exc}); pass --overwrite to start afresh") from None
            if _digest_json(stored) != _digest_json(description):
                keys = sorted(k for k in set(stored) | set(description) if stored.get(k) != description.get(k))
                raise FileExistsError(f"{self.out} holds a run with other {', '.join(keys)}; pass --overwrite "
                                      "to replace it, or choose another output folder")
        elif self.out.is_dir() and any(self.out.iterdir()):
            raise FileExistsError(f"{self.out} exists and is not empty (no {RUN_FILE}: not a fuzzrisk monitor "
                                  "run); choose another output folder, or pass --overwrite")
        (self.out / SCENES_DIR).mkdir(parents=True, exist_ok=True)
        if not run_path.is_file():
            write_text(run_path, json.dumps(description, indent=1))
        self.scenes = [self._open(plan, Shield(shield)) for plan in plans]
        self._by_name = {s.plan.name: s for s in self.scenes}
        self.resumed = sum(s.done for s in self.scenes)

    def _remove_own_files(self) -> None:
        for name in (RUN_FILE, SUMMARY_FILE):
            (self.out / name).unlink(missing_ok=True)
        scenes = self.out / SCENES_DIR
        if scenes.is_dir():
            for path in scenes.iterdir():
                if path.suffix in (".jsonl", ".png") and path.is_file():
                    path.unlink()

    def _open(self, plan: ScenePlan, shield: Shield) -> _Scene:
        path = self.out / SCENES_DIR / f"{scene_file_stem(plan.name)}.jsonl"
        scene = _Scene(plan, path, shield, plan.keys())
        if path.is_file():
            data = path.read_bytes()
            end = data.rfind(b"\n") + 1
            if end < len(data):  # a torn last line from an interruption: dropped
                with open(path, "r+b") as f:
                    f.truncate(end)
            for n, line in enumerate(data[:end].decode("utf-8").splitlines(), start=1):
                self._check_line(scene, path, n, line)
        scene.handle = open(path, "a", encoding="utf-8")
        return scene

    def _check_line(self, scene: _Scene, path: Path, n: int, line: str) -> None:
        where = f"{path}: line {n}"
        try:
            row = json.loads(line)
        except json.JSONDecodeError as exc:
            raise ValueError(f"{where}: not valid JSON ({exc}); the output is damaged: pass --overwrite") from None
        k = scene.done
        if k >= scene.plan.n_frames:
            raise ValueError(f"{where}: scene {scene.plan.name!r} has {scene.plan.n_frames} frames and this "
                             "line is one more; pass --overwrite")
        expected = (scene.plan.name, k, scene.keys[k])
        got = tuple(row.get(f) if isinstance(row, dict) else None for f in ("scene", "frame", "key"))
        if got != expected:
            raise ValueError(f"{where}: is frame {got}, expected (scene, frame, key) = {expected}; "
                             "pass --overwrite")
        processed = row.get("status") != UNPROCESSED
        for name in ("ego_speed",) + (_REPLAYED if processed else ()):
            if name not in row:
                raise ValueError(f"{where}: has no {name!r} field, which a resume needs (a line of an older "
                                 "fuzzrisk monitor?); pass --overwrite to start afresh")
        if processed:
            try:
                decision = scene.shield.update(row["risk"], speed=row["ego_speed"],
                                               unseen=_stored_rows(row["unseen"], 3), time=row["time"],
                                               emerged=_stored_shares(row["emerged"]),
                                               walkers=_stored_rows(row["walkers"], 2),
                                               contact=_stored_shares(row["unseen_contact"]))
            except (ValueError, TypeError) as exc:
                raise ValueError(f"{where}: the shield cannot replay this line ({exc}); pass --overwrite") \
                    from None
            if row["shield"] != {"engaged": decision.engaged, "deceleration": decision.deceleration}:
                raise ValueError(f"{where}: shield {row['shield']} does not replay (this run's shield "
                                 f"gives {decision}); pass --overwrite")
        scene.take(row)

    def pending(self) -> list[Chunk]:
        """The chunks of frames still to do, scene by scene, in order."""
        return [chunk for s in self.scenes for chunk in s.plan.chunks(s.done)]

    @property
    def remaining(self) -> int:
        """Frames still to do."""
        return sum(s.plan.n_frames - s.done for s in self.scenes)

    def add(self, results: list[FrameResult]) -> list[dict]:
        """Append the rows of ``results`` (in order), flush them to disk; return the rows."""
        rows, touched = [], []
        for result in results:
            scene = self._by_name[result.scene]
            if result.index != scene.done:
                raise RuntimeError(f"result for {result.scene!r} frame {result.index} arrived when frame "
                                   f"{scene.done} was due (results must come in order)")
            if result.observation is None:
                row, scene.earlier = report_row(result, None, None, None), []
            else:
                report = result.observation.report
                moved = result.ego_speed * (result.timestamp - scene.time[-1]) if scene.earlier else 0.0
                before, scene.earlier = shift_earlier(scene.earlier, report, moved)
                emerged = unseen_emerged(report, before, self.retriever) if self.measure_emerged else None
                decision = scene.shield.update(report.risk, speed=result.ego_speed, unseen=report.unseen,
                                               time=result.timestamp, emerged=emerged, walkers=result.walkers,
                                               contact=report.unseen_contact)
                row = report_row(result, decision.engaged, decision.deceleration, emerged)
            scene.handle.write(json.dumps(row, allow_nan=False) + "\n")
            scene.take(row)
            rows.append(row)
            if scene not in touched:
                touched.append(scene)
        for scene in touched:
            scene.handle.flush()
            os.fsync(scene.handle.fileno())
            if scene.complete:
                self._timeline(scene)
        return rows

    def _timeline(self, scene: _Scene) -> Path:
        return save_risk_timeline([{"name": scene.plan.name, "time": scene.time, "risk": scene.risk,
                                    "target": scene.target, "status": scene.status}],
                                  scene.path.with_suffix(".png"), self.threshold)

    def table(self) -> list[dict]:
        """Per scene: frames, statuses, risk, shield and target statistics."""
        rows = []
        for s in self.scenes:
            risk, target = np.array(s.risk, dtype=np.float64), np.array(s.target, dtype=np.float64)
            rows.append({
                "scene": s.plan.name, "condition": s.plan.condition, "frames": s.done,
                **{status: s.status.count(status) for status in STATUSES + (UNPROCESSED,)},
                "mean_risk": float(np.nanmean(risk)) if np.isfinite(risk).any() else None,
                "max_risk": float(np.nanmax(risk)) if np.isfinite(risk).any() else None,
                "shield_on": float(np.mean(s.engaged)) if s.engaged else None,
                "mean_target": float(np.nanmean(target)) if np.isfinite(target).any() else None,
            })
        return rows

    def close(self, notes: list[str]) -> Path:
        """Close the files, draw missing timelines of complete scenes, write ``summary.md``."""
        for s in self.scenes:
            s.handle.close()
            if s.complete and not s.path.with_suffix(".png").is_file():
                self._timeline(s)
        lines = ["# fuzzrisk monitor run", ""] + [f"> {n}" for n in notes] + ["", "## Scenes", "",
                                                                              format_table(self.table(), COLUMNS,
                                                                                           markdown=True), ""]
        errors = self.errors()
        if errors:
            lines += [f"## Frames that could not be processed ({len(errors)})", ""]
            lines += [f"- {scene} frame {index} ({key}): {error}" for scene, index, key, error in errors] + [""]
        lines += ["## Risk timelines", ""]
        for s in self.scenes:
            png = s.path.with_suffix(".png")
            if png.is_file():
                lines += [f"![{s.plan.name}]({SCENES_DIR}/{png.name})", ""]
        path = self.out / SUMMARY_FILE
        write_text(path, "\n".join(lines))
        return path

    def errors(self) -> list[tuple[str, int, str, str]]:
        """(scene, frame, key, error) of every frame that could not be processed."""
        return [(s.plan.name, *e) for s in self.scenes for e in s.errors]


#: the summary table's columns
COLUMNS = [("scene", "scene", "{}"), ("condition", "condition", "{}"), ("frames", "frames", "{}"),
           *[(status, status, "{}") for status in STATUSES + (UNPROCESSED,)], ("mean_risk", "mean risk", "{:.2f}"),
           ("max_risk", "max risk", "{:.2f}"), ("shield_on", "shield", "{:.0%}"),
           ("mean_target", "1-USC~", "{:.2f}")]
