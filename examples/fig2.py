# %% [markdown]
# # Fig. 2: friction against driving velocity (strong bonds)
#
# The letter's Fig. 2 from Python: "two sliding regimes (at low and high velocities) with
# a stick-slip region between them". The sweep is the one of docs/results.md, section
# "Fig. 2: velocity sweep" (`stickslip sweep scenarios/fig2.toml --param plate.v
# --log-range 0.05:20:14 --replicas 4`), run on a Dask LocalCluster; its table is the
# CLI's `sweep.csv`, byte for byte. Then two friction traces, one in each regime.
#
# Needs the package with Dask and matplotlib:
# `pip install './python[dask]' matplotlib`, then `python examples/fig2.py` from the
# repository root (about 10 s on 2 cores), or open it as a notebook (the `# %%` cells)
# in Jupyter (jupytext) or VS Code. Writes `out/fig2-python/` (the sweep's files and
# `fig2.png`).

# %%
from pathlib import Path

import matplotlib.pyplot as plt

import stickslip

SCENE = Path("scenarios/fig2.toml")
OUT = Path("out/fig2-python")
OUT.mkdir(parents=True, exist_ok=True)

# %% [markdown]
# ## The sweep
# 14 velocities evenly spaced in log V from 0.05 to 20, 4 replicas each (seeds derived
# from the scene's seed, the grid point and the replica, as the CLI derives them).

# %%
if __name__ == "__main__":  # the LocalCluster's worker processes import this file
    table = stickslip.sweep(SCENE, "plate.v", stickslip.log_range("0.05:20:14"), replicas=4, log=True, out=OUT)
    print(table[["plate.v", "friction_per_junction", "friction_per_junction_ci95", "regime", "stick_slip_fraction"]])

# %% [markdown]
# ## One trace in each regime
# Smooth sliding at V = 0.1, stick-slip at V = 1: the friction per junction over the last
# 300 time units of each run.

# %%
if __name__ == "__main__":
    traces = {v: stickslip.run(SCENE, plate__v=v, output__plot=False).trace for v in (0.1, 1.0)}

# %% [markdown]
# ## The figure
# Left: friction per junction against V (means with 95% Student-t intervals across the
# replicas), stick-slip grid points filled, the stick-slip range shaded. Right: the traces.

# %%
if __name__ == "__main__":
    n = table["friction_mean"].iloc[0] / table["friction_per_junction"].iloc[0]  # junctions N
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    ss = table["regime"] == "stick-slip"
    if ss.any():
        v = table["plate.v"]
        ax.axvspan(v[ss].min(), v[ss].max(), color="tab:orange", alpha=0.15, label="stick-slip (SS)")
    ax.errorbar(
        table["plate.v"],
        table["friction_per_junction"],
        yerr=table["friction_per_junction_ci95"],
        fmt="-",
        color="tab:blue",
        capsize=3,
    )
    ax.plot(table["plate.v"][~ss], table["friction_per_junction"][~ss], "o", mfc="white", color="tab:blue",
            label="sliding (SI)")
    ax.plot(table["plate.v"][ss], table["friction_per_junction"][ss], "o", color="tab:blue", label="stick-slip")
    ax.set_xscale("log")
    ax.set_xlabel("driving velocity V")
    ax.set_ylabel("friction per junction F/N")
    ax.set_title("Fig. 2: velocity dependence (strong bonds)")
    ax.legend(frameon=False)

    for v, tr in traces.items():
        last = tr[tr["t"] >= tr["t"].iloc[-1] - 300]
        bx.plot(last["t"], last["friction"] / n, lw=0.8, label=f"V = {v:g}")
    bx.set_xlabel("time t")
    bx.set_ylabel("friction per junction F/N")
    bx.set_title("friction against time")
    bx.set_ylim(0, 1.1 * max(tr["friction"].max() / n for tr in traces.values()) + 0.1)
    bx.legend(frameon=False, loc="upper center", ncols=2)
    fig.tight_layout()
    fig.savefig(OUT / "fig2.png", dpi=120)
    print(f"wrote {OUT / 'fig2.png'}")
