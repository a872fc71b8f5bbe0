"""Two recorded runs side by side: ``rov-console compare A.mcap B.mcap``.

Each recording is debriefed as ``rov-console report`` debriefs it (``app.report.debrief``:
the run that flew a mission's legs, scored from its recorded rows). The two are aligned at
one moment each (the mission's start, the first contact with the frame, the recording's
start, or the first event whose text holds given words), and compared figure by figure: the
mission's RMS errors, thrust and saturation, each leg's duration and errors (legs matched by
their number), the landing, the alarms. Each row says which run did better, where "better"
has a meaning (lower error, less time saturated, a landing that succeeded); a figure that is
not a matter of better or worse (a duration of a leg that waits for the current) says
"same" or "" with no winner.

What differs between the runs' set-ups (mission, parameter set, seed, gains, allocation)
is said first: a comparison of different missions is allowed, but it is not a like-for-like
one, and the reader is told so.
"""

from __future__ import annotations

import html
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from app.report import Debrief, debrief, png_html, table_html

ALIGN_CHOICES = ("mission", "contact", "start")
"""Where two runs are aligned, besides ``event:WORDS`` (the first event whose text holds
WORDS, a note for instance)."""

SAME_RELATIVE = 0.02
"""Two figures within 2 % of each other (or both within ``SAME_ABSOLUTE``) are the same: the
debrief's RMS from 20 Hz rows agrees with the run's 100 Hz figure to about that
(``tests/test_report.py``), so a smaller difference says nothing."""
SAME_ABSOLUTE = 1e-3

SETUP_KEYS = (
    "params_name", "params", "seed", "settings", "gains", "current", "crane_tip_n",
    "docking_frame", "wire_length_m",
)  # fmt: skip
"""The keys of a recording's set-up record compared to say what differs (a dictionary's
entries one by one: ``settings.allocation``)."""


@dataclass(frozen=True)
class Difference:
    """One figure of both runs."""

    figure: str
    unit: str
    a: float | str | None
    b: float | str | None
    better: str
    """"a", "b", "same", or "" when better or worse has no meaning for the figure or either
    run has no value."""

    def as_dict(self) -> dict:
        return {"figure": self.figure, "unit": self.unit, "a": self.a, "b": self.b,
                "better": self.better}  # fmt: skip


@dataclass(frozen=True)
class Aligned:
    """The moment each run is aligned at, in its recording's time [s]."""

    at: str
    a_s: float
    b_s: float

    def as_dict(self) -> dict:
        return {"event": self.at, "a_s": self.a_s, "b_s": self.b_s}


@dataclass(frozen=True)
class Comparison:
    a_path: Path
    b_path: Path
    a: Debrief
    b: Debrief
    aligned: Aligned
    differs: list[str]
    """What differs between the runs' set-ups, in words (empty: the same set-up)."""
    differences: list[Difference]

    def as_dict(self) -> dict:
        return {
            "a": str(self.a_path),
            "b": str(self.b_path),
            "a_name": self.a.name,
            "b_name": self.b.name,
            "aligned_at": self.aligned.as_dict(),
            "differs": self.differs,
            "differences": [d.as_dict() for d in self.differences],
        }


class CompareError(ValueError):
    """A comparison that cannot be made (a bad alignment, a run without the moment)."""


def _lower_is_better(a: float | None, b: float | None) -> str:
    if a is None or b is None or not (math.isfinite(a) and math.isfinite(b)):
        return ""
    if abs(a - b) <= max(SAME_ABSOLUTE, SAME_RELATIVE * max(abs(a), abs(b))):
        return "same"
    return "a" if a < b else "b"


def _no_winner(a: float | None, b: float | None) -> str:
    return "same" if _lower_is_better(a, b) == "same" else ""


def _figure(value: float | None) -> float | None:
    """A figure for the table: None for a missing or non-finite one."""
    if value is None or not math.isfinite(value):
        return None
    return float(value)


def _alarms_raised(d: Debrief) -> int:
    return sum(
        1
        for e in d.events
        if e.get("kind") == "alarm" and (e.get("data") or {}).get("active", True)
    )


def _first_event(d: Debrief, kinds: tuple[str, ...], words: str = "") -> float | None:
    for e in d.events:
        if e.get("kind") in kinds and words.lower() in str(e.get("text", "")).lower():
            return float(e["t_s"])
    return None


def _moment(d: Debrief, align: str, which: str) -> float:
    """Where run ``d`` is aligned, in its recording's time [s] (CompareError when it has no
    such moment)."""
    t0 = float(d.t_s[0])
    if align == "start":
        return t0
    if align == "mission":
        t = _first_event(d, ("leg", "mission"))
        return t if t is not None else t0
    if align == "contact":
        contacts = [ld.t_contact_s for ld in d.result.landings if math.isfinite(ld.t_contact_s)]
        if not contacts:
            raise CompareError(f"run {which} ({d.name}) never touched the frame: align elsewhere")
        return t0 + min(contacts)
    check_align(align)
    words = align[6:].strip()
    t = _first_event(d, tuple({str(e.get("kind")) for e in d.events}), words)
    if t is None:
        raise CompareError(f"run {which} ({d.name}) has no event whose text holds {words!r}")
    return t


def check_align(align: str) -> None:
    """CompareError unless ``align`` is one of ``ALIGN_CHOICES`` or event:WORDS: said before
    either log is read."""
    if align in ALIGN_CHOICES or (align.startswith("event:") and align[6:].strip()):
        return
    raise CompareError(
        f"align must be one of {', '.join(ALIGN_CHOICES)} or event:WORDS, got {align!r}"
    )


def _setup_words(key: str, a: object, b: object) -> str:
    def show(v: object) -> str:
        text = str(v)
        return text if len(text) <= 60 else text[:57] + "..."

    return f"{key}: {show(a)} against {show(b)}"


def what_differs(a: Debrief, b: Debrief) -> list[str]:
    """What differs between the runs' set-ups, in words, the mission's name first."""
    out = []
    if a.name != b.name:
        out.append(_setup_words("mission", a.name, b.name))
    elif a.setup.get("mission_toml") != b.setup.get("mission_toml"):
        out.append("mission file: the same name, different contents")
    for key in SETUP_KEYS:
        va, vb = a.setup.get(key), b.setup.get(key)
        if va == vb:
            continue
        if isinstance(va, dict) and isinstance(vb, dict) and key != "params":
            for sub in sorted(set(va) | set(vb)):
                if va.get(sub) != vb.get(sub):
                    out.append(_setup_words(f"{key}.{sub}", va.get(sub), vb.get(sub)))
        elif key == "params" and a.setup.get("params_name") != b.setup.get("params_name"):
            continue  # said by params_name
        else:
            out.append(_setup_words(key, va, vb))
    return out


def _differences(a: Debrief, b: Debrief) -> list[Difference]:
    ra, rb = a.result, b.result
    rows: list[Difference] = []

    def lower(figure: str, unit: str, va: float | None, vb: float | None) -> None:
        fa, fb = _figure(va), _figure(vb)
        rows.append(Difference(figure, unit, fa, fb, _lower_is_better(fa, fb)))

    def plain(figure: str, unit: str, va: float | None, vb: float | None) -> None:
        fa, fb = _figure(va), _figure(vb)
        rows.append(Difference(figure, unit, fa, fb, _no_winner(fa, fb)))

    for key, label, unit in (
        ("rms_north_m", "RMS north error", "m"),
        ("rms_east_m", "RMS east error", "m"),
        ("rms_heading_deg", "RMS heading error", "deg"),
        ("saturated_time_s", "time saturated", "s"),
        ("max_thruster_utilisation", "largest thruster use", "-"),
    ):
        lower(label, unit, getattr(ra, key), getattr(rb, key))
    lower("thrust spent", "N s", a.thrust_impulse_newton_s, b.thrust_impulse_newton_s)
    lower("alarms raised", "", _alarms_raised(a), _alarms_raised(b))
    plain("duration", "s", a.duration_s, b.duration_s)
    legs_b = {leg.index: leg for leg in rb.legs}
    for leg in ra.legs:
        other = legs_b.get(leg.index)
        name = f"leg {leg.index} ({leg.name or leg.type})"
        plain(f"{name}: duration", "s", leg.duration_s, other.duration_s if other else None)
        for key, label, unit in (
            ("rms_north_m", "RMS north", "m"),
            ("rms_east_m", "RMS east", "m"),
            ("rms_heading_deg", "RMS heading", "deg"),
            ("saturated_s", "saturated", "s"),
        ):
            lower(f"{name}: {label}", unit, getattr(leg, key), getattr(other, key, None))
    la = ra.landings[0] if ra.landings else None
    lb = rb.landings[0] if rb.landings else None
    if la is not None or lb is not None:
        landed = {None: None, True: "landed", False: "failed"}
        sa = landed[la.success if la else None]
        sb = landed[lb.success if lb else None]
        if sa is None or sb is None:
            better = "a" if sa == "landed" else "b" if sb == "landed" else ""
        else:
            better = "same" if sa == sb else ("a" if sa == "landed" else "b")
        rows.append(Difference("landing", "", sa or "none", sb or "none", better))
        for key, label, unit in (
            ("miss_m", "landing: miss at the post tops", "m"),
            ("contact_speed_mps", "landing: contact speed", "m/s"),
            ("heading_error_deg", "landing: heading error", "deg"),
        ):
            va = abs(getattr(la, key)) if la is not None else None
            vb = abs(getattr(lb, key)) if lb is not None else None
            lower(label, unit, va, vb)
    return rows


def compare(a_path: str | Path, b_path: str | Path, align: str = "mission") -> Comparison:
    """Compare two recordings (ValueError naming the file when one cannot be read,
    CompareError when the alignment cannot be made)."""
    check_align(align)
    a, b = debrief(a_path), debrief(b_path)
    aligned = Aligned(align, _moment(a, align, "A"), _moment(b, align, "B"))
    return Comparison(
        Path(a_path), Path(b_path), a, b, aligned, what_differs(a, b), _differences(a, b)
    )


def plot_comparison(c: Comparison, out: Path) -> Path:
    """Both runs on one time axis (seconds from the moment they are aligned at): the tree's
    north, east and heading errors against its reference, and the largest thruster use."""
    from app.plots import comparison_figure

    series: list[tuple[np.ndarray, ...]] = []
    for d, t_align in ((c.a, c.aligned.a_s), (c.b, c.aligned.b_s)):
        log = d.log
        assert log is not None  # a debrief always keeps its rows
        tree, ref = log["tree_eta_n"], log["eta_ref_n"]
        heading = np.degrees(np.angle(np.exp(1j * (tree[:, 5] - ref[:, 2]))))
        use = np.max(np.abs(log["thruster_utilisation"]), axis=1)
        series.append(
            (
                log.t_s - t_align,
                tree[:, 0] - ref[:, 0],
                tree[:, 1] - ref[:, 1],
                heading,
                use,
            )
        )
    labels = (f"A: {c.a.name} ({c.a_path.name})", f"B: {c.b.name} ({c.b_path.name})")
    return comparison_figure(series, labels, c.aligned.at, out)


def _cell(value: float | str | None) -> str:
    if value is None:
        return "-"
    if isinstance(value, str):
        return value
    return f"{value:.3g}" if abs(value) < 1e4 else f"{value:.0f}"


def table_rows(c: Comparison) -> list[tuple[str, str, str, str]]:
    """(figure with its unit, A, B, better) per difference, as printed."""
    return [
        (
            f"{d.figure} [{d.unit}]" if d.unit else d.figure,
            _cell(d.a),
            _cell(d.b),
            {"a": "A", "b": "B", "same": "same"}.get(d.better, ""),
        )
        for d in c.differences
    ]


def comparison_html(c: Comparison, plot: Path | None = None) -> str:
    """The comparison as a section of the debrief report."""
    differs = "".join(f"<li>{html.escape(x)}</li>" for x in c.differs)
    said = (
        f"<p>Not a like-for-like comparison: the set-ups differ.</p><ul>{differs}</ul>"
        if c.differs
        else "<p>The same set-up (mission, parameter set, seed, gains).</p>"
    )
    aligned = (
        f"<p>A is this run ({html.escape(c.a_path.name)}), B is "
        f"{html.escape(c.b_path.name)} ({html.escape(c.b.name)}); aligned at "
        f"{html.escape(c.aligned.at)}: A's {c.aligned.a_s:.1f} s with B's "
        f"{c.aligned.b_s:.1f} s.</p>"
    )
    figure = f"<figure>{png_html(plot)}</figure>" if plot is not None else ""
    table = table_html(("figure", "A", "B", "better"), table_rows(c))
    return f"<h2>Compared with another run</h2>{aligned}{said}{table}{figure}"


def comparison_image(c: Comparison) -> np.ndarray:
    """``plot_comparison``'s figure as an RGB image (height, width, 3), for a page."""
    import tempfile

    from matplotlib import image

    with tempfile.TemporaryDirectory() as tmp:
        rgba = image.imread(plot_comparison(c, Path(tmp) / "comparison.png"))
    return (np.clip(rgba[..., :3], 0.0, 1.0) * 255).astype(np.uint8)
