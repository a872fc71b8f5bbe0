"""The planner's figures: the operability table and the weather window's timeline (PNG,
matplotlib, drawn from the JSON the commands print)."""

from __future__ import annotations

import textwrap
from datetime import datetime
from pathlib import Path

COLOURS = {
    None: "#b7e1b0",
    "slack_wire": "#e07b7b",
    "snap_load": "#b05da8",
    "contact_speed": "#f2b25c",
    "miss": "#7aa6d8",
    "saturation": "#c9a27e",
    "landed": "#a0a0a0",
}
"""A cell's colour by its limiting criterion (None: within every limit)."""


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def table_figure(data: dict, path: Path) -> Path:
    """Left: the allowable Hs per Tp (columns) and wave heading (rows), with what limits it.
    Right: every cell, Hs rising up each heading's block, coloured by its limiting criterion,
    with the seeds within the limits over the seeds run."""
    from matplotlib.patches import Patch

    plt = _plt()
    tps = sorted({c["tp_s"] for c in data["cells"]})
    heads = sorted({c["wave_heading_deg"] for c in data["cells"]})
    hss = sorted({c["hs_m"] for c in data["cells"]})
    fig, (ax1, ax2) = plt.subplots(
        1, 2, figsize=(4 + 1.6 * len(tps) * 2, 2.5 + 0.55 * len(heads) * (1 + len(hss)) / 2)
    )
    allow = {(a["tp_s"], a["wave_heading_deg"]): a for a in data["allowable"]}
    for i, h in enumerate(heads):
        for j, tp in enumerate(tps):
            a = allow[(tp, h)]
            ax1.add_patch(plt.Rectangle((j, i), 1, 1, color=COLOURS[a["limiting"]], ec="w"))
            more = "+" if a["above_grid"] else ""
            lim = a["limiting"] or "none in grid"
            one = a["hs_m_first_seed"]
            seed = f"\n(1 seed: {one:g} m)" if one != a["hs_m"] else ""
            ax1.text(
                j + 0.5,
                i + 0.5,
                f"{a['hs_m']:g}{more} m\n{lim}{seed}",
                ha="center",
                va="center",
                fontsize=8,
            )
    _axes(ax1, tps, heads, "allowable Hs per Tp and wave heading")
    rows = [(h, hs) for h in heads for hs in hss]
    cells = {(c["wave_heading_deg"], c["hs_m"], c["tp_s"]): c for c in data["cells"]}
    for i, (h, hs) in enumerate(rows):
        for j, tp in enumerate(tps):
            c = cells[(h, hs, tp)]
            ax2.add_patch(plt.Rectangle((j, i), 1, 1, color=COLOURS[c["limiting"]], ec="w"))
            ax2.text(
                j + 0.5,
                i + 0.5,
                f"{c['seeds_ok']}/{c['seeds']}",
                ha="center",
                va="center",
                fontsize=7,
            )
    ax2.set_xlim(0, len(tps))
    ax2.set_ylim(0, len(rows))
    ax2.set_xticks([j + 0.5 for j in range(len(tps))], [f"{t:g}" for t in tps])
    ax2.set_yticks(
        [i + 0.5 for i in range(len(rows))],
        [f"{h:g} deg, Hs {hs:g} m" for h, hs in rows],
        fontsize=7,
    )
    ax2.set_xlabel("Tp [s]")
    ax2.set_title("each cell: seeds within the limits / seeds run", fontsize=9)
    for k in range(1, len(heads)):
        ax2.axhline(k * len(hss), color="k", lw=1.2)
    used = [k for k in COLOURS if any(c["limiting"] == k for c in data["cells"])]
    ax2.legend(
        handles=[Patch(color=COLOURS[k], label=k or "within the limits") for k in used],
        loc="upper left",
        bbox_to_anchor=(1.01, 1.0),
        fontsize=7,
    )
    comp = "on" if data["heave_compensation"] else "off"
    cur = data["current"]
    title = (
        f"{data['mission']}: vessel heading {data['vessel_heading_deg']:g} deg, heave "
        f"compensation {comp}, current {cur['speed_mps']:g} m/s towards "
        f"{cur['direction_deg']:g} deg; wave heading 180 = head sea, 90 = towards starboard. "
        + "Limits: "
        + ", ".join(
            f"{lim['name']} {lim['value']:g} {lim['unit']}".strip()
            for lim in data["limits"]
            if lim["name"] != "landed"
        )
        + f". {data['seed_dependence']}"
    )
    fig.suptitle("\n".join(textwrap.wrap(title, 150)), fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _axes(ax, tps: list[float], heads: list[float], title: str) -> None:
    ax.set_xlim(0, len(tps))
    ax.set_ylim(0, len(heads))
    ax.set_xticks([j + 0.5 for j in range(len(tps))], [f"{t:g}" for t in tps])
    ax.set_yticks([i + 0.5 for i in range(len(heads))], [f"{h:g}" for h in heads])
    ax.set_xlabel("Tp [s]")
    ax.set_ylabel("wave heading relative to the vessel [deg]")
    ax.set_title(title, fontsize=9)


def window_figure(data: dict, path: Path) -> Path:
    """The forecast's Hs against the operational limit (alpha times the table's allowable
    Hs), go and no-go hours, and the windows long enough for the operation."""
    plt = _plt()
    hours = data["hours"]
    t = [datetime.fromisoformat(h["time"].replace("Z", "+00:00")) for h in hours]
    step = t[1] - t[0] if len(t) > 1 else None
    fig, (ax, band) = plt.subplots(
        2, 1, figsize=(11, 4.8), sharex=True, gridspec_kw={"height_ratios": [4, 1]}
    )
    ax.plot(t, [h["hs_m"] for h in hours], "-o", ms=3, lw=1.2, label="forecast Hs")
    limit = [h["limit_hs_m"] if h["limit_hs_m"] is not None else float("nan") for h in hours]
    ax.step(
        t,
        limit,
        where="post",
        color="tab:red",
        lw=1.2,
        label="operational limit: alpha x allowable Hs",
    )
    design = [
        h["allowable_hs_m"] if h["allowable_hs_m"] is not None else float("nan") for h in hours
    ]
    ax.step(
        t, design, where="post", color="tab:red", lw=0.8, ls=":", label="allowable Hs (the table)"
    )
    for w in data["windows"]:
        ax.axvspan(_time(w["start"]), _time(w["end"]), color="tab:green", alpha=0.15, lw=0)
    ax.set_ylabel("Hs [m]")
    ax.legend(fontsize=7, loc="upper right")
    for ti, h in zip(t, hours, strict=True):
        width = step if step is not None else None
        band.barh(
            0,
            width,
            left=ti,
            height=1,
            align="edge",
            lw=0,
            color="tab:green" if h["go"] else "tab:red",
        )
    band.set_yticks([])
    band.set_ylabel("go", rotation=0, labelpad=12)
    band.set_xlabel("time [UTC]")
    a = data["alpha_table"]
    n = len(data["windows"])
    title = (
        f"{data['mission']}: operation {data['operation_hours']:g} h + contingency "
        f"{data['contingency_hours']:g} h = reference period {data['reference_hours']:g} h; "
        f"alpha table {a['table']}, lowest alpha {data['alpha']:.3f}; {n} "
        f"window{'s' * (n != 1)} long enough (green)"
    )
    fig.suptitle("\n".join(textwrap.wrap(title, 140)), fontsize=8)
    fig.autofmt_xdate()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _time(text: str) -> datetime:
    return datetime.fromisoformat(text.replace("Z", "+00:00"))
