"""The suite's plot: time against achieved error, one log-log panel per engine."""

from __future__ import annotations

import math
import textwrap

#: Errors of exactly 0 are drawn hollow a decade below a panel's smallest positive
#: error (at this value when the panel has none).
ZERO_FLOOR = 1e-17


def plot_rows(rows, fh, title=None):
    """Draw ``rows`` (the suite's schema) into the open binary file ``fh`` as PNG.

    One panel per engine; x = achieved error, y = seconds (per ``per``), both log;
    one line per case, geomkit solid with circles, the reference dashed with squares
    in the same colour.  Exact zeros are drawn hollow a decade below the panel's
    smallest positive error.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    engines = list(dict.fromkeys(r["engine"] for r in rows))
    n = max(1, len(engines))
    cols = min(3, n)
    nrows = math.ceil(n / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(5.2 * cols, 4.2 * nrows), squeeze=False)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    for ax, eng in zip(axes.ravel(), engines):
        sub = [r for r in rows if r["engine"] == eng]
        cases = list(dict.fromkeys(r["case"] for r in sub))
        positive = [r[f"{w}_error"] for r in sub for w in ("geomkit", "reference")
                    if r[f"{w}_error"] is not None and 0 < r[f"{w}_error"] < math.inf]
        floor = min(positive) / 10 if positive else ZERO_FLOOR
        for k, case in enumerate(cases):
            colour = f"C{k % 10}"
            rs = [r for r in sub if r["case"] == case]
            for who, style, marker in (("geomkit", "-", "o"), ("reference", "--", "s")):
                pts = [(r[f"{who}_error"], r[f"{who}_seconds"]) for r in rs
                       if r[f"{who}_error"] is not None and r[f"{who}_seconds"] is not None
                       and math.isfinite(r[f"{who}_error"])]
                if not pts:
                    continue
                x = [e if e > 0 else floor for e, _ in pts]
                y = [t for _, t in pts]
                label = case if who == "geomkit" else f"{case}: {rs[0]['reference_name']}"
                ax.plot(x, y, style, color=colour, lw=1, alpha=0.7)
                full = [i for i, (e, _) in enumerate(pts) if e > 0]
                zero = [i for i, (e, _) in enumerate(pts) if e <= 0]
                ax.plot([x[i] for i in full], [y[i] for i in full], marker, color=colour,
                        ls="none", label=label)
                if zero:
                    ax.plot([x[i] for i in zero], [y[i] for i in zero], marker, ls="none",
                            mfc="none", color=colour)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(eng)
        ax.set_xlabel("achieved error (model units; hollow = 0)")
        ax.set_ylabel(f"seconds per {sub[0]['per']}")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=6, loc="best")
    # the subtitle (run conditions) is wrapped to the figure's width and the layout
    # leaves room for it; bbox "tight" keeps any overhang in the picture
    head = ["geomkit (solid, circles) vs reference (dashed, squares)"]
    if title:
        head += textwrap.wrap(str(title), width=int(24 * 5.2 * cols / 2.6))
    fig.suptitle("\n".join(head), fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.16 * len(head) / (4.2 * nrows)))
    fig.savefig(fh, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
