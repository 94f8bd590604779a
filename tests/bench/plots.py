"""PNG plots of the benchmarks (matplotlib, Agg backend: no display needed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

COLORS = {"CYCLES": "#d95f02", "DACRT": "#1b9e77", "DACRT_ADAPTIVE": "#7570b3",
          "embree": "#d95f02", "dacrt": "#1b9e77"}
LABEL = {"CYCLES": "Cycles", "DACRT": "DACRT", "DACRT_ADAPTIVE": "DACRT adaptive"}


def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _plain_log_ticks(ax) -> None:
    """Label only the decades of log axes (minor labels overlap on short ranges)."""
    from matplotlib.ticker import NullFormatter
    for axis, scale in ((ax.xaxis, ax.get_xscale()), (ax.yaxis, ax.get_yscale())):
        if scale == "log":
            axis.set_minor_formatter(NullFormatter())


def _save(fig, path: Path) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    _plt().close(fig)


def errortime(doc: dict, path: Path) -> None:
    """One log-log panel per scene: relMSE vs wall seconds, every seed as a dot, means joined."""
    plt = _plt()
    names = list(doc["summary"])
    cols = min(3, max(len(names), 1))
    rows = (len(names) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 3.8 * rows), squeeze=False)
    for ax, name in zip(axes.flat, names):
        sc = doc["summary"][name]
        for engine in ("CYCLES", "DACRT", "DACRT_ADAPTIVE"):
            if engine not in sc:
                continue
            rs = [r for r in doc["renders"] if r["scene"] == name and r["engine"] == engine]
            ax.scatter([r["seconds"] for r in rs], [r["relmse"] for r in rs], s=9, alpha=0.45,
                       color=COLORS[engine])
            pts = sc[engine]["points"]
            ax.plot([p["seconds"] for p in pts], [p["relmse"] for p in pts], "o-",
                    color=COLORS[engine], label=LABEL[engine])
            for p in pts:
                ax.annotate(f"{p['samples']}", (p["seconds"], p["relmse"]), fontsize=7,
                            xytext=(3, 3), textcoords="offset points")
        floor = doc["references"].get(name, {}).get("floor")
        if floor and np.isfinite(floor):
            ax.axhline(floor, color="grey", ls=":", lw=1, label="reference noise")
        ax.set_xscale("log")
        ax.set_yscale("log")
        _plain_log_ticks(ax)
        ax.set_title(name)
        ax.set_xlabel("wall seconds per render")
        ax.set_ylabel("relMSE")
        ax.grid(True, which="both", alpha=0.25)
        ax.legend(fontsize=8)
    for ax in list(axes.flat)[len(names):]:
        ax.axis("off")
    _save(fig, path)


def breakdown(doc: dict, path: Path) -> bool:
    """Stacked bars of DACRT's render time per scene (largest sample count). False if none."""
    from .report import _PARTS
    bars = []
    for name, sc in doc["summary"].items():
        for engine in ("DACRT", "DACRT_ADAPTIVE"):
            if engine in sc and "breakdown" in sc[engine]["points"][-1]:
                p = sc[engine]["points"][-1]
                bars.append((f"{name}\n{LABEL[engine]} {p['samples']} spp", p["breakdown"]))
    if not bars:
        return False
    plt = _plt()
    fig, ax = plt.subplots(figsize=(max(5, 1.6 * len(bars) + 2), 4.2))
    bottom = np.zeros(len(bars))
    cmap = plt.get_cmap("tab10")
    for i, part in enumerate(_PARTS):
        vals = np.array([b[part] for _, b in bars])
        ax.bar(range(len(bars)), vals, bottom=bottom, label=part, color=cmap(i))
        bottom += vals
    ax.set_xticks(range(len(bars)), [b[0] for b in bars], fontsize=8)
    ax.set_ylabel("wall seconds")
    ax.set_title("DACRT render time breakdown")
    ax.legend(fontsize=8, bbox_to_anchor=(1.01, 1), loc="upper left")
    _save(fig, path)
    return True


def lines(path: Path, panels: list[dict], title: str = "") -> None:
    """Generic panels: each {title, xlabel, ylabel, logx, logy, series: [{label, x, y, style}]}."""
    plt = _plt()
    fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 4.0), squeeze=False)
    for ax, panel in zip(axes.flat, panels):
        for s in panel["series"]:
            kw = {"color": s["color"]} if s.get("color") else {}
            ax.plot(s["x"], s["y"], s.get("style", "o-"), label=s["label"], **kw)
        if panel.get("logx"):
            ax.set_xscale("log")
        if panel.get("logy"):
            ax.set_yscale("log")
        _plain_log_ticks(ax)
        ax.set_title(panel.get("title", ""))
        ax.set_xlabel(panel.get("xlabel", ""))
        ax.set_ylabel(panel.get("ylabel", ""))
        ax.grid(True, which="both", alpha=0.25)
        ax.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    _save(fig, path)
