"""Campbell diagram of a reed study (``campbell.png``): natural frequencies against the engine
orders over engine speed.

Each stored mode frequency is a horizontal line (a band from its lowest to its highest value
when it varies over the design points); each engine order o (a multiple of the crankshaft
frequency: o = k·e for harmonic k of the reed's event frequency, e events per crank revolution
from the ``events_per_revolution`` response, so 0.5, 1, 1.5, … for a four-stroke) is the line
f = o·n/60, up to the study's ``max_order``; the study's speed range is shaded; the crossings
within it (the ``*_crossing_order`` / ``*_crossing_speed`` responses) are marked and labelled
with order and speed. Axes in rpm and Hz.
"""

from __future__ import annotations

import json

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

MODES = ("first", "second", "third", "fourth")
HATCHES = ("//", "\\\\", "..", "xx")
MAX_LABELS = 8  # crossings labelled with order and speed when there are no more than this
DEFAULT_MAX_ORDER = 3.0  # the scene's default max_order, for results that do not record it


def campbell_figure(ds: xr.Dataset) -> Figure | None:
    """The Campbell diagram, or None when the results lack the frequencies or the band."""
    needed = ("band_min", "band_max", "events_per_revolution", "first_frequency")
    if not all(n in ds.data_vars for n in needed):
        return None
    events = float(np.nanmax(ds["events_per_revolution"].values))
    speed_lo = float(np.nanmin(ds["band_min"].values)) * 60.0 / events
    speed_hi = float(np.nanmax(ds["band_max"].values)) * 60.0 / events
    modes = [m for m in MODES if f"{m}_frequency" in ds.data_vars]
    crossings = _crossings(ds, modes)
    highest_order = max([_max_order(ds), *(k for k, _, _ in crossings)])
    orders = events * np.arange(1, round(highest_order / events) + 1)
    top = 1.25 * speed_hi
    fig = Figure(figsize=(7.0, 4.6), layout="constrained")
    ax = fig.subplots()
    ax.axvspan(speed_lo, speed_hi, color="0.9", label="speed range", zorder=0)
    speed = np.array([0.0, top])
    highest = 0.0
    for order in orders:
        f = order * speed / 60.0
        ax.plot(speed, f, color="0.45", lw=0.8, zorder=1)
        ax.annotate(f"{order:g}", (top, f[-1]), xytext=(3, 0), textcoords="offset points",
                    fontsize="small", color="0.3", va="center")  # fmt: skip
        highest = f[-1]
    for j, m in enumerate(modes):
        values = ds[f"{m}_frequency"].values
        lo, hi = float(np.nanmin(values)), float(np.nanmax(values))
        colour = f"C{j}"
        label = (
            f"{m} mode {lo:.4g} Hz"
            if hi <= lo * (1 + 1e-9)
            else f"{m} mode over the designs: {lo:.4g}–{hi:.4g} Hz"
        )
        if lo > highest:
            label += " (above every order line)"
        if hi > lo * (1 + 1e-9):  # hatched and outlined: overlapping bands stay apart
            ax.axhspan(lo, hi, facecolor="none", edgecolor=colour, hatch=HATCHES[j % 4], lw=1.0,
                       zorder=2, label=label)  # fmt: skip
        else:
            ax.axhline(lo, color=colour, lw=1.5, zorder=2, label=label)
    if crossings:
        speeds = [n for _, n, _ in crossings]
        frequencies = [f for _, _, f in crossings]
        label = f"crossings in range ({len(crossings)})"
        ax.plot(speeds, frequencies, "o", color="C3", ms=5, zorder=3, label=label)
    if len(crossings) <= MAX_LABELS:  # more would overlap: the orders are numbered at the right
        for order, speed_rpm, frequency in crossings:
            ax.annotate(f"order {order:g}\n{speed_rpm:.0f} rpm", (speed_rpm, frequency),
                        xytext=(4, 4), textcoords="offset points", fontsize="x-small",
                        color="C3")  # fmt: skip
    lowest = min(float(np.nanmin(ds[f"{m}_frequency"].values)) for m in modes)
    ax.set_xlim(0.0, top)
    ax.set_ylim(0.0, max(highest, 1.3 * lowest))
    ax.set_xlabel("engine speed [rpm]")
    ax.set_ylabel("frequency [Hz]")
    ax.set_title(
        f"Campbell diagram: engine orders {orders[0]:g}…{orders[-1]:g} (numbered at the right)\n"
        f"orders are multiples of crankshaft speed; the reed opens {events:g}× per revolution",
        fontsize="medium",
    )
    ax.legend(loc="upper left", fontsize="small")
    return fig


def _max_order(ds: xr.Dataset) -> float:
    """The study's ``max_order`` setting (the scene's default when the results lack it)."""
    settings = json.loads(ds.attrs.get("settings", "{}"))
    return float(settings.get("max_order", DEFAULT_MAX_ORDER))


def _crossings(ds: xr.Dataset, modes: list[str]) -> list[tuple[float, float, float]]:
    """Distinct (order, speed [rpm], frequency [Hz]) crossings in the speed range, lowest
    order first."""
    found = set()
    for m in modes:
        order, speed = f"{m}_crossing_order", f"{m}_crossing_speed"
        if order not in ds.data_vars or speed not in ds.data_vars:
            continue
        frequency = ds[f"{m}_frequency"].values
        for k, n, f in zip(ds[order].values, ds[speed].values, frequency, strict=True):
            if np.isfinite(k) and np.isfinite(n):
                found.add((float(k), round(float(n), 1), float(f)))
    return sorted(found)
