"""The cost of a Dask sweep: its throughput on a LocalCluster against a Rust loop over the same
identifications on a rayon pool, on the same machine.

    python python/examples/dask_throughput.py [--workers 2] [--repeats 3]

The cases are the grid of python/tests/test_dask.py (10 noise levels x 20 seeds; 500 samples and
50 bootstrap resamples each), each `simulate(samples, noise, seed)` then `identify(x, t=t,
bootstrap, seed)`. Four timings, the best of `--repeats` each:

- rust:   the cases on a rayon pool of `--workers` threads, in the extension, without Python;
- dask:   the cases as tasks on LocalCluster(n_workers=--workers, threads_per_worker=1), results
          (Identification objects) gathered to the client: one case per task, and `--batch` cases
          per task;
- empty:  as many Dask tasks that do nothing but return as many bytes as an Identification
          pickles to: Dask's own cost per task;
- rust/1 and python/1: Rust alone on a pool of one thread, and the Python loop in this process
          (whose library calls use rayon's global pool), to tell the cost of the Python layer from
          the cost of Dask.

Every Dask result is checked against the Rust loop's JSON for the same case. Build the package
in release (`pip install ./python`) before timing.
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import sys
import time

import hbid
from hbid import _hbid

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import dask_sweep  # noqa: E402

NOISE = [0.001, 0.002, 0.003, 0.005, 0.007, 0.01, 0.015, 0.02, 0.03, 0.05]
SEEDS = range(20)
SAMPLES = 500
BOOTSTRAP = 50


def empty_task(i: int, size: int) -> bytes:
    """A task that does nothing and returns as many bytes as an Identification pickles to: the
    cost of Dask itself (scheduling, messages, pickling) per task."""
    return bytes(size)


def best(repeats: int, run) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--batch", type=int, default=4, help="cases per task of the batched sweep")
    args = parser.parse_args()

    from dask.distributed import Client, LocalCluster
    import cloudpickle

    cloudpickle.register_pickle_by_value(dask_sweep)
    cases = [(n, s) for n in NOISE for s in SEEDS]
    n = len(cases)

    def rust(threads: int):
        return lambda: _hbid.rayon_sweep(cases, samples=SAMPLES, bootstrap=BOOTSTRAP, threads=threads)

    reference = rust(args.workers)()

    # Each worker runs one task at a time; RAYON_NUM_THREADS=1 also keeps the library's own
    # parallel loops (assembly, bootstrap) on that one thread, as docs/python.md recommends.
    cluster = LocalCluster(
        n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None,
        env={"RAYON_NUM_THREADS": "1"},
    )
    with cluster, Client(cluster) as client:
        def sweep():
            futures = client.map(
                dask_sweep.case, [a for a, _ in cases], [b for _, b in cases],
                samples=SAMPLES, bootstrap=BOOTSTRAP, pure=False,
            )
            return dict(client.gather(futures))

        def batched():
            futures = client.map(
                dask_sweep.batch, dask_sweep.batches(cases, args.batch),
                samples=SAMPLES, bootstrap=BOOTSTRAP, pure=False,
            )
            return dict(pair for rows in client.gather(futures) for pair in rows)

        results = sweep()  # warm: workers import hbid and receive the function
        if batched() != results:
            raise SystemExit("batched and per-case tasks differ")
        # interleaved, so that a change of the machine's load touches both alike
        size = len(pickle.dumps(results[cases[0]]))

        def empty():
            futures = client.map(empty_task, range(n), size=size, pure=False)
            return client.gather(futures)

        timings = {"rust": [], "dask": [], "batched": [], "rust1": [], "python1": [], "empty": []}
        for _ in range(args.repeats):
            timings["rust"].append(best(1, rust(args.workers)))
            timings["dask"].append(best(1, sweep))
            timings["batched"].append(best(1, batched))
            timings["rust1"].append(best(1, rust(1)))
            timings["python1"].append(best(1, lambda: [dask_sweep.case(a, b, SAMPLES, BOOTSTRAP) for a, b in cases]))
            timings["empty"].append(best(1, empty))
    rust, dask, batched_s, rust1, python1, empty_s = (
        min(timings[k]) for k in ("rust", "dask", "batched", "rust1", "python1", "empty")
    )
    for (case, expected) in zip(cases, reference):
        if json.loads(results[case].to_json()) != json.loads(expected):
            raise SystemExit(f"case {case}: Dask and the Rust loop differ")

    print(f"{n} identifications ({SAMPLES} samples, {BOOTSTRAP} bootstrap resamples each), best of {args.repeats}")
    print(f"{'':<40} {'seconds':>8} {'per second':>11}")
    rows = [
        (f"rust, rayon, {args.workers} threads", rust),
        (f"dask, LocalCluster, {args.workers} workers", dask),
        (f"dask, batches of {args.batch} cases", batched_s),
        ("rust, 1 thread", rust1),
        ("python loop (global rayon pool)", python1),
        (f"dask, {n} empty tasks ({size} B results)", empty_s),
    ]
    for name, seconds in rows:
        print(f"{name:<40} {seconds:>8.3f} {n / seconds:>11.1f}")
    print(f"dask / rayon throughput: {rust / dask:.1%} (a case per task), {rust / batched_s:.1%} (batches of {args.batch})")
    print(f"rayon speed-up on {args.workers} threads: {rust1 / rust:.2f}")
    print("results identical: every case's JSON")


if __name__ == "__main__":
    main()
