"""The benchmarks' plots, drawn from their results alone (no measuring): the work-precision
study's cost against error and energy error per scene, and the throughput study's steps per
second of the vector environment and its peers.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from roller_gym.bench.verdicts import chaotic, default_run, error_of, family, horizon

Results = dict[str, Any]

OUR_FAMILIES = ("euler", "rk4", "rk4 auto", "rk8", "rk8 auto", "taylor", "taylor auto",
                "midpoint", "dop853")
MJ_FAMILIES = ("MuJoCo default", "MuJoCo tuned")
COLORS = {"euler": "tab:red", "rk4": "tab:blue", "rk4 auto": "tab:green", "rk8": "tab:cyan",
          "rk8 auto": "tab:olive", "taylor": "tab:pink", "taylor auto": "black",
          "midpoint": "tab:purple", "dop853": "tab:gray",
          "MuJoCo default": "tab:orange", "MuJoCo tuned": "tab:brown"}
MARKERS = {"euler": "v", "rk4": "o", "rk4 auto": "s", "rk8": "h", "rk8 auto": "p",
           "taylor": "<", "taylor auto": "*",
           "midpoint": "D", "dop853": "^", "MuJoCo default": "X", "MuJoCo tuned": "P"}
#: The work-precision page's plots, in the docs folder's ``benchmarks`` folder.
WORK_PRECISION_PLOTS = ("work_precision.png", "work_precision_local.png", "energy.png")
#: The throughput page's plot.
THROUGHPUT_PLOT = "throughput.png"


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _scene_panels(count: int, panel_height: float, legend_in: float) -> tuple[Any, Any]:
    """A figure of ``count`` panels, three to a row, ``panel_height`` inches each, with
    ``legend_in`` inches below them for the legend."""
    plt = _pyplot()
    cols = min(3, count)
    rows = math.ceil(count / cols)
    height = panel_height * rows + legend_in
    return plt.subplots(rows, cols, figsize=(5.2 * cols, height), squeeze=False)


def _save_panels(fig: Any, axes: Any, count: int, legend_in: float, legend_columns: int,
                 title: str, path: Path) -> None:
    """Blank the unused panels, put the first panel's legend in the ``legend_in`` inches under
    them, title, save, close."""
    for ax in axes.flat[count:]:
        ax.axis("off")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=legend_columns, fontsize=8)
    fig.suptitle(title)
    height = fig.get_figheight()
    fig.tight_layout(rect=(0, legend_in / height, 1, 1 - 0.4 / height))
    fig.savefig(path, dpi=110)
    _pyplot().close(fig)


def plot_work_precision(results: Results, path: Path, metric: str) -> None:
    """Cost against error, one panel per scene: the global or the local error."""
    st = results["settings"]
    scenes = results["scenes"]
    legend_in = 1.3  # inches under the plots for the legend
    fig, axes = _scene_panels(len(scenes), panel_height=4.2, legend_in=legend_in)
    for ax, sc in zip(axes.flat, scenes, strict=False):
        hz = horizon(results, sc)
        for fam in (*OUR_FAMILIES, *MJ_FAMILIES):
            # in the order of the setting (substeps up, tolerance down, timestep down)
            # (runs that blew up past 100 rad are left out: they are in the tables)
            pts = [(error_of(r, metric), r["seconds"] / hz) for r in family(sc, fam)
                   if error_of(r, metric) <= 100.0]
            if pts:
                e, c = zip(*pts, strict=True)
                ax.loglog(np.maximum(e, 1e-16), c, marker=MARKERS[fam], color=COLORS[fam],
                          label=fam, lw=1.2, ms=5, ls="--" if fam.startswith("MuJoCo") else "-")
        d = default_run(sc)
        ax.loglog([max(error_of(d, metric), 1e-16)], [d["seconds"] / hz], "*", color="k",
                  ms=15, label=f"default ({st['method']}, tol {st['tolerance']:.0e})", zorder=5)
        if metric == "global":
            ax.axvline(max(sc["reference"]["own_error"][0], 1e-16), color="k", lw=0.8, ls=":",
                       label="reference's own error")
            ax.axvline(st["target_error"], color="tab:red", lw=0.8, ls="-.",
                       label=f"target {st['target_error']:g} rad")
        else:
            ax.axvline(st["tolerance"], color="tab:red", lw=0.8, ls="-.",
                       label=f"tolerance {st['tolerance']:.0e}")
        title = f"{sc['name']}: {sc['note']}"
        if metric == "global" and chaotic(results, sc):
            title += (f"\n(chaotic: the reference itself is off by {st['target_error']:g} at "
                      f"{sc['reference']['predictable_s']:g} s)")
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(f"largest |φ error| over {hz:g} s [rad]" if metric == "global"
                      else "largest |φ error| of one control step [rad]")
        ax.set_ylabel("wall time per simulated second [s]")
        ax.grid(True, which="major", alpha=0.3)
    _save_panels(fig, axes, len(scenes), legend_in, 6,
                 f"Work-precision, {metric} error: cost against error (lower left is better), "
                 "all measured in the same run", path)


def plot_energy(results: Results, path: Path) -> None:
    """The energy error at zero torque against time, one panel per scene."""
    scenes = results["scenes"]
    legend_in = 1.0
    fig, axes = _scene_panels(len(scenes), panel_height=3.8, legend_in=legend_in)
    for ax, sc in zip(axes.flat, scenes, strict=False):
        for item in sc["energy"]:
            t, value = item["curve"]["t"], item["curve"]["value"]
            ax.loglog(t, np.clip(np.asarray(value, dtype=float), 1e-17, 1e2), lw=1,
                      label=item["label"])
        ax.set_ylim(1e-17, 1e2)  # a blow-up leaves the plot at the top
        ax.set_title(sc["name"], fontsize=9)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("|E − E0| / E0 (largest in each interval)")
        ax.grid(True, alpha=0.3)
    _save_panels(fig, axes, len(scenes), legend_in, 4,
                 f"Energy error at zero torque over {results['config']['energy_horizon_s']:g} s "
                 "(from rest at φ0)", path)


def plot_throughput(results: Results, path: Path) -> None:
    """Steps per second of the vector environment, its physics kernel alone and each peer
    measured, per number of sub-environments (the throughput study's results)."""
    plt = _pyplot()
    vector = results["vector"]
    sizes = sorted(vector, key=int)
    names = ["ours", "kernel", "CartPoleVectorEnv",
             *sorted({k for v in vector.values() for k in v if "Pendulum" in k})]
    labels = {"ours": "roller_gym/RollerStabilize-v2 (make_vec)",
              "kernel": "its physics kernel alone", "CartPoleVectorEnv": "CartPoleVectorEnv"}
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    width = 0.8 / len(names)
    for i, name in enumerate(names):
        x = [j + (i - (len(names) - 1) / 2) * width for j in range(len(sizes))]
        ax.bar(x, [vector[n].get(name, 0.0) / 1e6 for n in sizes], width,
               label=labels.get(name, name), hatch="//" if name == "kernel" else None)
    ax.set_xticks(range(len(sizes)), [f"{int(n):,}" for n in sizes])
    ax.set_xlabel("sub-environments")
    ax.set_ylabel("million environment steps per second")
    ax.set_title("Vector environments, whole episodes of random actions (best of repeats)")
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def work_precision_plots(results: Results, folder: Path) -> list[Path]:
    """Every plot of the work-precision page into ``folder``; their paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / name for name in WORK_PRECISION_PLOTS]
    plot_work_precision(results, paths[0], "global")
    plot_work_precision(results, paths[1], "local")
    plot_energy(results, paths[2])
    return paths
