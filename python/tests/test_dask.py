"""Sweeps on Dask: 200 identifications on a LocalCluster of 2 worker processes give exactly
the results of the serial loop, seed for seed."""

from __future__ import annotations

import pathlib
import sys

import pytest

distributed = pytest.importorskip("distributed")
cloudpickle = pytest.importorskip("cloudpickle")

import hbid  # noqa: E402

EXAMPLES = pathlib.Path(__file__).resolve().parents[1] / "examples"
sys.path.insert(0, str(EXAMPLES))
import dask_sweep  # noqa: E402

# The workers cannot import the example from their own path: ship its functions by value.
cloudpickle.register_pickle_by_value(dask_sweep)

NOISE = [0.001, 0.002, 0.003, 0.005, 0.007, 0.01, 0.015, 0.02, 0.03, 0.05]
SEEDS = range(20)
# A small record per identification (20 forcing periods) keeps 200 of them to seconds.
SAMPLES = 500
BOOTSTRAP = 50


def test_a_sweep_on_a_local_cluster_equals_the_serial_loop():
    cases = [(noise, seed) for noise in NOISE for seed in SEEDS]
    assert len(cases) == 200
    serial = dict(dask_sweep.case(n, s, SAMPLES, BOOTSTRAP) for n, s in cases)
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    with cluster, distributed.Client(cluster) as client:
        futures = client.map(dask_sweep.case, [n for n, _ in cases], [s for _, s in cases], samples=SAMPLES, bootstrap=BOOTSTRAP)
        parallel = dict(client.gather(futures))
        workers = {w for w in client.who_has(futures).values() for w in w}
    assert len(workers) == 2
    assert parallel.keys() == serial.keys()
    for key in cases:
        assert parallel[key] == serial[key], key
    # the results are real identifications, and the seeds matter
    assert all(abs(r.coefficients["sin(t)*cos(x)"] + 1.52) < 0.2 for r in serial.values())
    assert len({r.intervals["sin(t)*cos(x)"] for r in serial.values()}) == len(cases)
    rows = dask_sweep.table(parallel)
    assert len(rows) == 200 and all(r["f_low"] <= r["f"] <= r["f_high"] for r in rows)
