"""Monte-Carlo identification of the paper's wing on a Dask cluster.

Each task makes one noisy realisation of the wing's stepped-sine data (the
exact first-order harmonic balance of the unloaded HAR wing, Table 3 with
Table 7's nonlinear terms, at the five levels of Table 2, up-sweeps over
5.3-5.5 Hz, with relative amplitude noise) and fits the generalised
power-law model to it with the linear part held (as the paper does after
its linear identification). The fitted parameters of all realisations are
written as a CSV and their distributions as a figure.

    python montecarlo_dask.py [--n N] [--workers W] [--scheduler ADDRESS] [--out DIR]

Without --scheduler, a LocalCluster of W worker processes (one thread each)
is started on this machine. With --scheduler tcp://HOST:8786, the fits run
on that cluster: every worker needs this package installed
(`pip install ./crates/nlsdof-py`) in the same Python version.
"""

import argparse
import csv
import os
import pathlib
import time

import numpy as np

# The wing (SI): mass kg, k N/m, c N s/m, k_r N/m^(1+rho), c_e N (s/m)^(1+eta)
MASS, K, C = 0.26699, 306.7878, 0.1164
K_R, RHO, C_E, ETA = 85000.0, 4.0022, 0.01591, 3.03099
LEVELS_PP = (0.82, 1.24, 1.62, 2.00, 2.46)  # m/s^2 peak-to-peak (Table 2)
PARAMETERS = ("beta", "rho", "kappa", "eta")


def realisation(seed, noise=0.01, steps=60):
    """One noisy data set and its fit; returns the fitted parameters."""
    import nlsdof

    wing = nlsdof.Model(
        mass=MASS, stiffness=K, damping=C,
        nonlinear_stiffness=(K_R, RHO), nonlinear_damping=(C_E, ETA),
    )
    rng = np.random.default_rng(seed)
    f = np.linspace(5.3, 5.5, steps)
    cols = {"level": [], "gamma": [], "f_hz": [], "amplitude": [], "sweep": []}
    for i, pp in enumerate(LEVELS_PP):
        gamma = pp / 2.0  # zero-to-peak
        a = wing.sweep(gamma=gamma, f_hz=f).amplitude
        cols["level"] += [str(i + 1)] * steps
        cols["gamma"] += [gamma] * steps
        cols["f_hz"] += list(f)
        cols["amplitude"] += list(a * (1.0 + noise * rng.standard_normal(steps)))
        cols["sweep"] += ["up"] * steps
    t0 = time.perf_counter()
    res = nlsdof.fit(
        cols, model="generalised", mass=MASS,
        fix={"alpha": K / MASS, "delta": C / MASS}, seed=seed,
    )
    p = res.parameters
    row = {"seed": seed, "converged": res.converged, "cost": res.cost,
           "fit_s": time.perf_counter() - t0}
    row.update({name: p[name]["value"] for name in PARAMETERS})
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=64, help="realisations (default 64)")
    ap.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes (default 2)")
    ap.add_argument("--scheduler", help="address of a running Dask scheduler, e.g. tcp://10.0.0.5:8786")
    ap.add_argument("--noise", type=float, default=0.01, help="relative amplitude noise (default 0.01)")
    ap.add_argument("--out", default="montecarlo", help="output folder (default ./montecarlo)")
    ap.add_argument("--threads-per-fit", type=int, default=None,
                    help="threads of one fit (the landscape runs in parallel; default: the "
                         "local cores divided among the workers)")
    args = ap.parse_args()
    if args.n < 1 or args.workers < 1:
        ap.error("--n and --workers must be at least 1")
    # each fit parallelises its landscape over RAYON_NUM_THREADS threads;
    # local worker processes inherit this environment
    threads = args.threads_per_fit or max(1, (os.cpu_count() or 1) // args.workers)
    os.environ["RAYON_NUM_THREADS"] = str(threads)

    from dask.distributed import Client, LocalCluster

    if args.scheduler:
        client, cluster = Client(args.scheduler), None
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    try:
        t0 = time.perf_counter()
        futures = client.map(realisation, range(args.n), noise=args.noise, pure=False)
        rows = client.gather(futures)
        wall = time.perf_counter() - t0
    finally:
        client.close()
        if cluster is not None:
            cluster.close()

    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows.sort(key=lambda r: r["seed"])
    with open(out / "parameters.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    truth = {"beta": K_R / MASS, "rho": RHO, "kappa": C_E / MASS, "eta": ETA}
    units = {"beta": "1/(s^2 m^rho)", "rho": "-", "kappa": "(s/m)^eta / s", "eta": "-"}
    fig, axes = plt.subplots(1, len(PARAMETERS), figsize=(4 * len(PARAMETERS), 3.4))
    for ax, name in zip(axes, PARAMETERS):
        v = np.array([r[name] for r in rows])
        t = truth[name]
        label = f"{name} [{units[name]}]"
        if name == "beta":
            # beta a^rho is what the data fix: beta spans decades with rho
            v, t, label = np.log10(v), np.log10(t), f"log10 beta, beta in {units[name]}"
        ax.hist(v, bins=max(5, int(np.sqrt(len(v)))), color="#1f77b4")
        ax.axvline(t, color="#d62728", label="truth")
        ax.set_xlabel(label)
        ax.set_title(f"mean {v.mean():.4g}, sd {v.std(ddof=1) if len(v) > 1 else 0:.2g}")
    axes[0].set_ylabel("realisations")
    axes[0].legend()
    fig.suptitle(f"Wing, {args.n} realisations with {100 * args.noise:g} % noise: fitted generalised model")
    fig.tight_layout()
    fig.savefig(out / "parameters.png", dpi=110)

    converged = sum(r["converged"] for r in rows)
    print(f"{args.n} fits ({converged} converged) in {wall:.2f} s: {args.n / wall:.2f} fits/s "
          f"on {'the cluster at ' + args.scheduler if args.scheduler else str(args.workers) + ' local worker(s)'}"
          f" ({threads} thread(s) per fit)")
    print(f"wrote {out / 'parameters.csv'} and {out / 'parameters.png'}")


if __name__ == "__main__":
    main()
