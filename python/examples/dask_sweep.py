"""A sweep of identifications on Dask: noise levels x seeds, gathered into one table.

Each task simulates the paper's pendulum as an encoder with Gaussian noise of its level reports
it, identifies it by the weak form with bootstrap intervals, and returns one row keyed by
(noise, seed). Every task is seeded and idempotent, so a task that a worker lost and the
scheduler ran again gives the same row, and the table is the same on any cluster.

    python python/examples/dask_sweep.py                  # a LocalCluster of 2 worker processes
    python python/examples/dask_sweep.py --scheduler tcp://host:8786   # a running cluster
    python python/examples/dask_sweep.py --slurm 4        # 4 Slurm jobs via dask-jobqueue

See docs/python.md for the cluster recipes and what must hold for them.
"""

from __future__ import annotations

import argparse
import time
from typing import Dict, List, Tuple

import hbid

#: The sweep's grid: noise standard deviations (radians) x bootstrap seeds.
NOISE = [0.001, 0.002, 0.005, 0.01, 0.02]
SEEDS = list(range(8))
#: Samples per record: 60 forcing periods of the paper's 25 samples.
SAMPLES = 1500
#: Bootstrap resamples per identification.
BOOTSTRAP = 200


def case(noise: float, seed: int, samples: int = SAMPLES, bootstrap: int = BOOTSTRAP) -> Tuple[Tuple[float, int], hbid.Identification]:
    """One identification, keyed by its settings: the record is simulated from `seed` (its
    noise) and the bootstrap draws from `seed` too, so the result depends on nothing else."""
    sim = hbid.simulate(samples=samples, noise=noise, seed=seed)
    result = hbid.identify(sim.x, t=sim.t, bootstrap=bootstrap, seed=seed)
    return (noise, seed), result


def batch(cases: List[Tuple[float, int]], samples: int = SAMPLES, bootstrap: int = BOOTSTRAP) -> List[Tuple[Tuple[float, int], hbid.Identification]]:
    """Several cases in one task: with cases of a few milliseconds, Dask's own cost per task
    (a few milliseconds of scheduling and messages) is paid once per batch instead."""
    return [case(noise, seed, samples, bootstrap) for noise, seed in cases]


def batches(cases: List[Tuple[float, int]], size: int) -> List[List[Tuple[float, int]]]:
    """The cases in batches of `size`, in order."""
    return [cases[i : i + size] for i in range(0, len(cases), size)]


def table(results: Dict[Tuple[float, int], hbid.Identification]) -> List[dict]:
    """One row per (noise, seed): the drive coefficient, its interval and the damping."""
    rows = []
    for (noise, seed), r in sorted(results.items()):
        lo, hi = r.intervals["sin(t)*cos(x)"]
        rows.append(
            {
                "noise": noise,
                "seed": seed,
                "f": -r.coefficients["sin(t)*cos(x)"],
                "f_low": -hi,
                "f_high": -lo,
                "c": r.coefficients["x'"],
                "k": r.coefficients["sin(x)"],
            }
        )
    return rows


def client_from(args: argparse.Namespace):
    from dask.distributed import Client, LocalCluster

    if args.scheduler:
        return Client(args.scheduler)
    if args.slurm:
        from dask_jobqueue import SLURMCluster  # pip install dask-jobqueue

        cluster = SLURMCluster(cores=1, processes=1, memory="2GB", walltime="00:30:00")
        cluster.scale(jobs=args.slurm)
        return Client(cluster)
    return Client(LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler")
    parser.add_argument("--slurm", type=int, help="Slurm jobs to start with dask-jobqueue")
    parser.add_argument("--batch", type=int, default=4, help="cases per task")
    args = parser.parse_args()

    with client_from(args) as client:
        start = time.perf_counter()
        cases = [(noise, seed) for noise in NOISE for seed in SEEDS]
        futures = client.map(batch, batches(cases, args.batch), pure=True)
        results = dict(pair for rows in client.gather(futures) for pair in rows)
        elapsed = time.perf_counter() - start
    rows = table(results)
    print(f"{len(rows)} identifications in {elapsed:.1f} s")
    print(f"{'noise':>7} {'seed':>4} {'f':>10} {'95 % interval':>23} {'c':>9} {'k':>9}")
    for r in rows:
        print(
            f"{r['noise']:>7.3f} {r['seed']:>4d} {r['f']:>10.5f} [{r['f_low']:>9.5f}, {r['f_high']:>9.5f}]"
            f" {r['c']:>9.5f} {r['k']:>9.5f}"
        )


if __name__ == "__main__":
    main()
