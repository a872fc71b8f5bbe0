"""What a campaign found: per-point table, success rate with its 95 % Wilson interval, and the
operability envelope (per current, the runs that succeeded with their Wilson interval; the
largest current up to which at least 95 % of runs succeed only when success falls with
current), against depth and per parameter set, as tables (Markdown) and a PNG figure."""

from __future__ import annotations

import math
import re
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from missions import campaign as cm

THRESHOLD = 0.95
"""Success rate the envelope asks for."""
MAX_LEVELS = 12
"""A parameter with at most this many distinct values is grouped by value; more (a random
draw) are grouped into ``BINS`` equal-width bins, named by their centre."""
BINS = 8


@dataclass(frozen=True)
class Rate:
    runs: int
    successes: int

    @property
    def rate(self) -> float:
        return self.successes / self.runs if self.runs else math.nan

    @property
    def interval(self) -> tuple[float, float]:
        return cm.wilson_interval(self.successes, self.runs)

    def text(self) -> str:
        lo, hi = self.interval
        return f"{100 * self.rate:5.1f} % [{100 * lo:.1f}, {100 * hi:.1f}]"


def rate_of(rows: list[dict]) -> Rate:
    return Rate(len(rows), sum(bool(r["success"]) for r in rows))


def levels(values: list[float]) -> list[float]:
    """Each value's level: itself when there are few distinct values, else its bin's centre."""
    finite = [v for v in values if v is not None and math.isfinite(v)]
    if len(set(finite)) <= MAX_LEVELS:
        return list(values)
    lo, hi = min(finite), max(finite)
    width = (hi - lo) / BINS or 1.0
    out = []
    for v in values:
        if v is None or not math.isfinite(v):
            out.append(v)
            continue
        k = min(int((v - lo) / width), BINS - 1)
        out.append(round(lo + (k + 0.5) * width, 6))
    return out


def _fmt(value: object) -> str:
    if isinstance(value, float):
        return "-" if math.isnan(value) else f"{value:g}"
    return str(value)


def _stat(rows: list[dict], key: str, how: str) -> str:
    vals = [r[key] for r in rows if r.get(key) is not None and math.isfinite(r[key])]
    if not vals:
        return "-"
    value = {"max": max(vals), "median": float(np.median(vals)), "mean": float(np.mean(vals))}[how]
    return f"{value:.3g}"


def point_label(campaign: cm.Campaign, point: int) -> str:
    values = campaign.point_values(point)
    return ", ".join(f"{k}={_fmt(v)}" for k, v in values.items()) or "all runs"


POINT_COLUMNS = (
    "point",
    "runs",
    "success [95 % CI]",
    "landed",
    "miss m (median/max)",
    "heading err deg (max)",
    "contact m/s (max)",
    "RMS N/E m (mean)",
    "RMS psi deg (mean)",
    "saturated s (mean)",
    "diverged",
    "errors",
)


def point_table(campaign: cm.Campaign, rows: list[dict]) -> list[list[str]]:
    """One line per point of the campaign (the grid points times the cases)."""
    by_point: dict[int, list[dict]] = defaultdict(list)
    for r in rows:
        by_point[int(r["point"])].append(r)
    out = []
    for point in sorted(by_point):
        rs = by_point[point]
        landed = [r for r in rs if r["landed"] is not None]
        out.append(
            [
                point_label(campaign, point),
                str(len(rs)),
                rate_of(rs).text(),
                f"{sum(bool(r['landed']) for r in landed)}/{len(landed)}" if landed else "-",
                f"{_stat(rs, 'miss_m', 'median')}/{_stat(rs, 'miss_m', 'max')}",
                _stat(rs, "heading_error_deg", "max"),
                _stat(rs, "contact_speed_mps", "max"),
                f"{_stat(rs, 'rms_north_m', 'mean')}/{_stat(rs, 'rms_east_m', 'mean')}",
                _stat(rs, "rms_heading_deg", "mean"),
                _stat(rs, "saturated_time_s", "mean"),
                str(sum(bool(r["diverged"]) for r in rs)),
                str(sum(r["simulated_s"] is None for r in rs)),
            ]
        )
    return out


def failure_cause(row: dict) -> str:
    """Why a run failed, from its row (the first that applies)."""
    if row["simulated_s"] is None:
        return "run raised: " + str(row["error"]).split(":")[0]
    if row["diverged"]:
        return "diverged"
    if row["timed_out"]:
        return "a leg timed out"
    if row["landed"] is False:
        if "posts" in str(row.get("rests_on") or ""):
            return "landing: a funnel missed its post"
        return "landing: too fast"
    if row["error"]:
        return "leg failed: " + cause_words(str(row["error"]))
    return "other"


LEG_FAILED = re.compile(r"^leg # \([a-z_-]+\) failed$")
"""The driver's prefix of a leg's failure, before the cause (numbers already '#')."""
CAUSE_MAX = 100
"""Longest cause text; a longer one is cut at a word, with an ellipsis."""


def cause_words(error: str) -> str:
    """An error's cause: its first clause (up to ': ', where the figures of the case follow),
    numbers as '#' (the same failure with other numbers is the same cause), cut at a word."""
    text = re.sub(r"-?\d+(\.\d+)?", "#", error.strip())
    clauses = text.split(": ")
    keep = 2 if LEG_FAILED.match(clauses[0]) else 1  # "leg # (dock) failed: <the cause>"
    text = ": ".join(clauses[:keep]).strip()
    if len(text) <= CAUSE_MAX:
        return text
    return text[:CAUSE_MAX].rsplit(" ", 1)[0] + " ..."


FAILURE_COLUMNS = ("cause", "runs", "saturated s (mean)", "max utilisation (mean)", "miss m (mean)")


def failure_table(rows: list[dict]) -> list[list[str]]:
    """Failed runs by cause, with how hard the thrusters worked in them; the last line gives
    the same for the runs that succeeded, to compare."""
    by_cause: dict[str, list[dict]] = defaultdict(list)
    for r in rows:
        if not r["success"]:
            by_cause[failure_cause(r)].append(r)
    ok = [r for r in rows if r["success"]]
    out = []
    ranked = sorted(by_cause.items(), key=lambda kv: -len(kv[1]))
    for cause, rs in [*ranked, ("(succeeded)", ok)]:
        out.append(
            [
                cause,
                str(len(rs)),
                _stat(rs, "saturated_time_s", "mean"),
                _stat(rs, "max_thruster_utilisation", "mean"),
                _stat(rs, "miss_m", "mean"),
            ]
        )
    return out


@dataclass(frozen=True)
class EnvelopeRow:
    params: str
    depth_m: float
    currents: tuple[float, ...]
    rates: tuple[Rate, ...]
    largest_mps: float | None
    """Largest tested current with every current up to it at >= 95 % success (None: not even
    the lowest)."""

    @property
    def passing(self) -> tuple[float, ...]:
        """The tested currents with at least ``THRESHOLD`` of their runs succeeding."""
        return tuple(c for c, r in zip(self.currents, self.rates, strict=True) if _passes(r))

    @property
    def is_threshold(self) -> bool:
        """Success falls with current here: the currents that pass are the lowest ones, so
        one largest current describes them. False when a stronger current passes above a
        weaker one that fails (the current can help: it pushes the tree towards the frame)."""
        return self.passing == self.currents[: len(self.passing)]

    def verdict(self) -> str:
        """What the data shows, in words: a largest current only when success falls with
        current; otherwise which currents pass and which fail."""
        if not self.is_threshold:
            failing = [c for c in self.currents if c not in self.passing]
            return (
                f"no single limit: >= {100 * THRESHOLD:.0f} % at {_speeds(self.passing)}, below at "
                f"{_speeds(failing)} (success does not fall with current here)"
            )
        if self.largest_mps is None:
            lowest = self.currents[0]
            return f"none: below {100 * THRESHOLD:.0f} % from the lowest tested ({lowest:g} m/s)"
        if self.largest_mps == self.currents[-1]:
            return f"up to {self.largest_mps:g} m/s (all tested currents)"
        return f"up to {self.largest_mps:g} m/s"


def _passes(rate: Rate) -> bool:
    return rate.runs > 0 and rate.rate >= THRESHOLD


def _speeds(currents: list[float] | tuple[float, ...]) -> str:
    return ", ".join(f"{c:g}" for c in currents) + " m/s"


def rate_words(current: float, rate: Rate) -> str:
    """'0.35: 1/2 (3-97 %)': successes of runs at a current, with the 95 % Wilson interval."""
    lo, hi = rate.interval
    return f"{current:g}: {rate.successes}/{rate.runs} ({100 * lo:.0f}-{100 * hi:.0f} %)"


def envelope(rows: list[dict], threshold: float = THRESHOLD) -> list[EnvelopeRow]:
    """For each parameter set and depth: success against current speed, and the largest
    current up to which the success rate stays at or above ``threshold``."""
    if not rows:
        return []
    currents = levels([float(r["current_speed_mps"]) for r in rows])
    depths = levels([float(r["depth_m"]) for r in rows])
    groups: dict[tuple[str, float], dict[float, list[dict]]] = defaultdict(
        lambda: defaultdict(list)
    )
    for r, c, d in zip(rows, currents, depths, strict=True):
        groups[(str(r["params"]), d)][c].append(r)
    out = []
    for (params, depth), by_current in sorted(groups.items()):
        cs = tuple(sorted(by_current))
        rates = tuple(rate_of(by_current[c]) for c in cs)
        largest = None
        for c, rate in zip(cs, rates, strict=True):
            if rate.rate < threshold:
                break
            largest = c
        out.append(EnvelopeRow(params, depth, cs, rates, largest))
    return out


def markdown_table(header: tuple[str, ...] | list[str], body: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in body]
    return "\n".join(lines)


def envelope_table(env: list[EnvelopeRow]) -> list[list[str]]:
    return [
        [
            e.params,
            f"{e.depth_m:g}",
            e.verdict(),
            "; ".join(rate_words(c, r) for c, r in zip(e.currents, e.rates, strict=True)),
        ]
        for e in env
    ]


ENVELOPE_COLUMNS = (
    "parameter set",
    "depth m",
    "currents with >= 95 % success",
    "successes by current m/s (95 % Wilson interval)",
)


def envelope_figure(env: list[EnvelopeRow], path: Path, title: str) -> Path:
    """Left: success rate against current with 95 % Wilson intervals, one line per parameter
    set and depth. Right: the envelope's largest current against depth, per parameter set."""
    fig, (ax, ax_env) = plt.subplots(1, 2, figsize=(12, 4.8))
    all_cs = [c for e in env for c in e.currents]
    span = (max(all_cs) - min(all_cs)) if all_cs else 0.0
    for k, e in enumerate(env):
        # side by side, so the bars of series at the same current do not hide each other
        dodge = (k - (len(env) - 1) / 2) * 0.008 * (span or 1.0)
        cs = np.array(e.currents) + dodge
        rate = np.array([r.rate for r in e.rates])
        ci = np.array([r.interval for r in e.rates])
        ax.errorbar(
            cs,
            100 * rate,
            yerr=[100 * (rate - ci[:, 0]), 100 * (ci[:, 1] - rate)],
            marker="o",
            capsize=3,
            label=f"{e.params}, {e.depth_m:g} m",
        )
    ax.axhline(100 * THRESHOLD, color="0.4", ls="--", lw=1, label="95 %")
    ax.set_xlabel("current speed [m/s]")
    ax.set_ylabel("success [%] (bars: 95 % Wilson interval)")
    ax.set_ylim(-3, 103)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("success against current")
    by_params: dict[str, list[EnvelopeRow]] = defaultdict(list)
    for e in env:
        by_params[e.params].append(e)
    for params, es in by_params.items():
        es = sorted(es, key=lambda e: e.depth_m)
        depth = [e.depth_m for e in es]
        largest = [
            np.nan if e.largest_mps is None or not e.is_threshold else e.largest_mps for e in es
        ]
        line = ax_env.plot(depth, largest, marker="o", label=params)[0]
        for e in es:
            if not e.is_threshold:  # no single limit: mark the currents that pass
                ax_env.plot(
                    [e.depth_m] * len(e.passing), e.passing, marker="x", color=line.get_color()
                )
                continue
            if e.largest_mps is not None and e.largest_mps == e.currents[-1]:
                ax_env.annotate(
                    "all tested",
                    (e.depth_m, e.largest_mps),
                    textcoords="offset points",
                    xytext=(4, 4),
                    fontsize=8,
                    color=line.get_color(),
                )
            if e.largest_mps is None:
                ax_env.plot([e.depth_m], [e.currents[0]], marker="v", color=line.get_color(), ls="")
    ax_env.set_xlabel("tree depth [m]")
    ax_env.set_ylabel("largest current with >= 95 % success [m/s]")
    all_c = [c for e in env for c in e.currents]
    if all_c:
        ax_env.set_ylim(0, 1.1 * max(all_c))
    ax_env.grid(alpha=0.3)
    ax_env.legend(fontsize=8)
    ax_env.set_title("operability envelope (v: below the lowest; x: passing, no single limit)")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


@dataclass
class Report:
    overall: Rate
    points: list[list[str]]
    envelope: list[EnvelopeRow]
    markdown: str
    figure: Path | None
    rows: list[dict]


def make_report(campaign: cm.Campaign, rows: list[dict], out: Path) -> Report:
    """Tables and figure of a campaign's rows; writes ``report.md`` and ``envelope.png``."""
    overall = rate_of(rows)
    points = point_table(campaign, rows)
    env = envelope(rows)
    figure = None
    if env:
        figure = envelope_figure(env, out / "envelope.png", f"{campaign.name}: {len(rows)} runs")
    errors = sum(r["simulated_s"] is None for r in rows)
    lines = [
        f"# Campaign {campaign.name}",
        "",
        campaign.description,
        "",
        f"Runs with a row: {len(rows)} of {campaign.runs}; errors (runs that raised): {errors}.",
        f"Success (mission not failed): {overall.successes}/{overall.runs} = "
        f"{overall.text()} (95 % Wilson interval).",
        "",
        "## Points",
        "",
        markdown_table(POINT_COLUMNS, points),
        "",
        "## Failures by cause",
        "",
        markdown_table(FAILURE_COLUMNS, failure_table(rows)),
        "",
        "## Operability envelope",
        "",
        "Per parameter set and depth, the currents at which at least 95 % of runs succeeded. "
        "A single limit ('up to X m/s') is given only when success falls with current; the "
        "intervals say how far few runs a current can be trusted.",
        "",
        markdown_table(ENVELOPE_COLUMNS, envelope_table(env)),
        "",
    ]
    if figure is not None:
        lines.append(f"![envelope]({figure.name})")
    markdown = "\n".join(lines) + "\n"
    (out / "report.md").write_text(markdown)
    return Report(overall, points, env, markdown, figure, rows)
