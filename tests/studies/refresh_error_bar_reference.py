"""Refresh the scipy reference of the error-bar samples: run this file (about 9 CPU-minutes).

Solves the reference of every point of the samples of tests/valve_samples.py and
writes tests/studies/data/valve_error_bar_reference.nc: per sample and point the reference
lift on the 0.5° curve axis (NaN outside the point's integration window; stored as int32
counts of ``LIFT_QUANTUM``) and the reference outputs ``valve_samples.OUTPUTS``, with a digest
of the points' parameter rows, and how it was made in the global attributes. The error-bar
test (tests/studies/test_valve_error_bar.py) refuses a file whose digest does not match its
samples and re-solves a few points to check the file. Review the printed summary before
committing: a refresh is a claim that the new numbers are right.
"""

from __future__ import annotations

import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import scipy
import xarray as xr

from studies.scenes.valve.reference import accuracy as acc
from studies.scenes.valve.reference import valve_ivp

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # tests/, pytest's path
import valve_samples

FILE = valve_samples.REFERENCE_FILE
LIFT_QUANTUM = 1e-11
"""Resolution of the stored lift [m]: far below the smallest error the test compares."""
INT32_FILL = -(2**31)


def refresh() -> Path:
    plan = valve_samples.sample_plan(["max_lift"], "lanes", 0.0)
    axis = plan.scene.curve_coordinate(plan.settings)
    names = list(valve_samples.SEEDS)
    size = valve_samples.SIZE
    lift = np.full((len(names), size, axis.size), np.nan)
    outputs = np.full((len(names), size, len(valve_samples.OUTPUTS)), np.nan)
    digests = {}
    started = time.process_time()
    for s, name in enumerate(names):
        points = valve_samples.sample_points(plan, name)
        digests[name] = valve_samples.points_digest(points)
        lift[s], outputs[s] = valve_samples.reference_of(plan, points, np.arange(size))
        print(f"sample {name}: {time.process_time() - started:.0f} CPU-s", flush=True)
    commit = subprocess.run(
        ["git", "rev-parse", "HEAD"], capture_output=True, text=True, check=False
    ).stdout.strip()
    ds = xr.Dataset(
        {
            "lift": (("sample", "point", "angle"), lift, {"units": "m"}),
            **{
                name: (("sample", "point"), outputs[:, :, j], {"units": unit})
                for j, (name, unit) in enumerate(
                    zip(valve_samples.OUTPUTS, ("m", "rad", "m/s", "m"), strict=True)
                )
            },
        },
        coords={"sample": names, "angle": ("angle", axis, {"units": "degree"})},
        attrs={
            "made_by": "python tests/studies/refresh_error_bar_reference.py",
            "git_commit": commit,
            "samples": "tests/valve_samples.py: "
            + ", ".join(f"{name} seed {seed}" for name, seed in valve_samples.SEEDS.items()),
            "sample_ranges": " ".join(
                " ".join(part.split())
                for part in (valve_samples.__doc__ or "").split("\n\n")
                if part.startswith("Sample ")
            ),
            "points_digest": ",".join(f"{k}:{v}" for k, v in digests.items()),
            "reference": (
                f"scipy {scipy.__version__} solve_ivp DOP853 rtol {valve_samples.REFERENCE_RTOL} "
                f"atol 1e-14, restarted at every drive and seat switch, each step scanned at "
                f"{valve_ivp.SCAN_POINTS} points for a switch it stepped over; excitation: the "
                f"chain's unclipped lift every {acc.REFERENCE_TABLE_DEG} deg, clipped at the "
                "lash; outputs located on the dense output (valve_outputs.py)"
            ),
            "numpy": np.__version__,
            "python": platform.python_version(),
            "cpu_seconds": round(time.process_time() - started),
        },
    )
    encoding = {
        "lift": {
            "dtype": "int32",
            "scale_factor": LIFT_QUANTUM,
            "_FillValue": INT32_FILL,
            "zlib": True,
            "complevel": 9,
            "shuffle": True,
        }
    }
    FILE.parent.mkdir(parents=True, exist_ok=True)
    ds.to_netcdf(FILE, engine="netcdf4", format="NETCDF4", encoding=encoding)
    return FILE


if __name__ == "__main__":
    path = refresh()
    with xr.open_dataset(path) as written:
        print(written)
        for name in valve_samples.OUTPUTS:
            values = written[name].values
            print(f"{name}: {np.isfinite(values).sum(axis=1)} finite per sample")
    print(f"wrote {path} ({path.stat().st_size} bytes)")
