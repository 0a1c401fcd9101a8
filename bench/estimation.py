"""Benchmark: the estimators' step time and accuracy on flights of Ψ itself (on demand, not in CI).

Flight 5 (models/flight5.toml), the director's model of it (Ψ, 4 x 16 optic, compiled), from
2 m at 4 m/s under the nominal inputs with each pulse pointed at the estimator's estimate
(``--beam estimate``, a tracker; ``--beam follow``: at the true craft, which leaks the truth:
the craft then always sits where the capture peaks while a filter rightly expects the loss of
its uncertain offset; under a beam held on the pad axis, ``--beam pad``, the drawn starts and
winds carry the craft out of the 7 cm beam within a second, and no linearisation holds there):
``--flights`` seeded flights of ``--pulses`` pulses of Ψ with the process noise the model's Q
describes (``PsiEstimationModel.sample_next``; every noise at ``--scale`` of the defaults) and
a position camera (5 mm x scale) at each pulse. Each estimator chosen (``--estimators
ekf,ukf,mhe``; ukf: the unscented filter) filters every flight. Printed: the step time (median,
99th percentile) over all steps; the NEES (n = 17) and the camera's NIS (m = 3) averaged over
flights and pulses, with their two-sided 95 % bands χ²(N n) / N
(tests/control/estimation/test_ekf_filter.py); the RMSE per entry of s over the second half of
the flights against the truth; the NEES of blocks of s (their marginal covariance) per entry,
which says where a filter is overconfident; the unscented filter's predictions made as the
EKF's (a sigma point outside Ψ's domain). Target (issue 30): EKF step median <= 0.3 ms.

Timing on a loaded machine is not a measurement of the code: run it alone.

Run: ``python bench/estimation.py --estimators ekf,mhe`` (``--help`` for options).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import casadi as ca
import numpy as np
from scipy.stats import chi2

import lightcraft_opt as lc
from lightcraft_opt.control.estimation import Reading
from lightcraft_opt.control.estimation.ekf import EkfOptions, ExtendedKalmanFilter
from lightcraft_opt.control.estimation.kalman import prior_sigmas
from lightcraft_opt.control.estimation.mhe import MovingHorizonEstimator
from lightcraft_opt.control.estimation.mhe_options import MheOptions
from lightcraft_opt.control.estimation.psi_model import (
    ProcessNoise,
    PsiEstimationModel,
    estimation_model,
)
from lightcraft_opt.control.estimation.ukf import UkfOptions, UnscentedKalmanFilter
from lightcraft_opt.layout import PARAMETERS, STATE, initial_state, nominal_inputs

ROOT = Path(__file__).resolve().parents[1]
G = 9.80665  # m/s²


def camera() -> ca.Function:
    """Positions in L at the reading's time, dt [s] before the node."""
    x, p, dt = ca.SX.sym("x", STATE.size), ca.SX.sym("p", PARAMETERS.size), ca.SX.sym("dt")
    r, v = STATE.get("r_L", x), STATE.get("v_L", x)
    y = r - v * dt - 0.5 * G * dt**2 * ca.DM([0, 0, 1])
    return ca.Function("camera", [x, p, dt], [y], ["x", "p", "dt"], ["y"])


def estimators(
    model: PsiEstimationModel,
    scale: float,
    names: list[str],
    relinearize: str = "default",
    second_order: tuple[str, ...] = (),
) -> dict:
    """The estimators named, each with the same prior (the EKF's defaults times ``scale``);
    the MHE relinearises ``relinearize`` stages a pulse ("all", a number, or "default":
    :class:`MheOptions`'); the EKF and the MHE keep Ψ's curvature across ``second_order``."""
    ekf = EkfOptions()
    unmatched = prior_sigmas(ekf.prior, model.names, 1.0)[1]  # the MHE refuses those
    prior = tuple((n, scale * s) for n, s in ekf.prior if n not in unmatched)
    made: dict = {}
    for name in names:
        if name == "ekf":
            options = EkfOptions(
                prior=prior, prior_default=scale * ekf.prior_default, second_order=second_order
            )
            made[name] = ExtendedKalmanFilter(model, options)
        elif name == "ukf":
            options = UkfOptions(prior=prior, prior_default=scale * ekf.prior_default)
            made[name] = UnscentedKalmanFilter(model, options)
        elif name == "mhe":
            stages = {"default": MheOptions().relinearize, "all": None}.get(relinearize)
            options = MheOptions(
                prior_sigma=scale * ekf.prior_default,
                prior_sigmas=prior,
                relinearize=int(relinearize) if relinearize.isdigit() else stages,
                second_order=second_order,
            )
            made[name] = MovingHorizonEstimator(model, options)
        else:
            raise SystemExit(f"unknown estimator {name!r}; known: ekf, ukf, mhe")
    return made


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--estimators", default="ekf", help="comma-separated: ekf, ukf, mhe")
    parser.add_argument("--flights", type=int, default=50)
    parser.add_argument("--pulses", type=int, default=40)
    parser.add_argument("--scale", type=float, default=1.0, help="every noise times this")
    parser.add_argument(
        "--beam",
        choices=("estimate", "follow", "pad"),
        default="estimate",
        help="estimate: each pulse points at the estimator's estimate (a tracker); follow: "
        "at the true craft; pad: on the pad axis",
    )
    parser.add_argument(
        "--relinearize",
        default="default",
        help="the MHE's stages evaluated afresh a pulse: a number, all, or default (MheOptions')",
    )
    parser.add_argument(
        "--second-order",
        default="",
        help="the EKF's and the MHE's second-order entries, comma-separated (e.g. "
        "r_L[east],r_L[north], the offset; r_L[east],r_L[north],H_L,coning,wind_L,coupling, "
        "curvature.PSI_CURVES); empty: first order",
    )
    args = parser.parse_args()
    curved = tuple(e for e in args.second_order.split(",") if e)
    model = estimation_model(lc.load_model(ROOT / "models" / "flight5.toml"))
    camera_R = (args.scale * 0.005) ** 2 * np.eye(3)
    psi = PsiEstimationModel(
        model, {"camera": (camera(), camera_R)}, noise=ProcessNoise().scaled(args.scale)
    )
    x0 = initial_state(model, r_L=(0.0, 0.0, 2.0), v_L=(0.0, 0.0, 4.0))
    u = nominal_inputs(model, psi.psi.inputs)
    sigma0 = args.scale * EkfOptions().prior_sigmas(psi.names)  # the prior both start from
    for name, est in estimators(
        psi, args.scale, args.estimators.split(","), args.relinearize, curved
    ).items():
        times, nees, nis, errors = [], [], [], []
        linearised = 0
        blocks = {
            "r_L, v_L": [i for i, n in enumerate(psi.names) if n[:3] in ("r_L", "v_L")],
            "H_L": [i for i, n in enumerate(psi.names) if n.startswith("H_L")],
            "coning": [i for i, n in enumerate(psi.names) if n.startswith("coning")],
            "wind, coupling": list(range(psi.state_size, psi.n)),
        }
        per_block: dict[str, list[float]] = {b: [] for b in blocks}
        for run in range(args.flights):
            rng = np.random.default_rng(1000 + run)
            est.reset(x0, 0.0)
            s = psi.start(x0) + rng.normal(size=psi.n) * sigma0
            u_k = u
            for k in range(args.pulses):
                t = k * psi.period
                y = psi.measure("camera", s, 0.0)[0] + np.sqrt(camera_R[0, 0]) * rng.normal(size=3)
                e = est.step([Reading("camera", t, k, y)], u_k if k else None, t)
                u_k = u.copy()
                if args.beam == "estimate":
                    u_k[:2] = e.z[:2]  # the next pulse points at the estimate
                elif args.beam == "follow":
                    u_k[:2] = s[:2]  # at the craft itself
                times.append(e.seconds)
                err = s - np.concatenate([e.z, list(e.slow.values())])
                P = e.covariance
                d = np.sqrt(np.diag(P))
                nees.append(err / d @ np.linalg.solve(P / np.outer(d, d), err / d))
                for b, idx in blocks.items():
                    Pb, eb = P[np.ix_(idx, idx)], err[idx]
                    per_block[b].append(eb @ np.linalg.solve(Pb, eb) / len(idx))
                nis += [i.nis for i in getattr(est, "innovations", [])]
                if k >= args.pulses // 2:
                    errors.append(err)
                s = psi.sample_next(s, u_k, t, rng)
            linearised += getattr(est, "linearised", 0)
        N = args.flights
        ms = 1e3 * np.array(times)
        print(f"{name}: step median {np.median(ms):.3f} ms, p99 {np.percentile(ms, 99):.3f} ms")
        band = chi2.ppf([0.025, 0.975], N * psi.n) / N
        print(f"  NEES {np.mean(nees):.2f} (n {psi.n}, band {band[0]:.2f}-{band[1]:.2f})")
        print(
            "  NEES per entry of a block: "
            + ", ".join(f"{b} {np.mean(v):.2f}" for b, v in per_block.items())
        )
        if hasattr(est, "linearised"):
            print(f"  predictions linearised (a sigma point outside Ψ's domain): {linearised}")
        if nis:
            band = chi2.ppf([0.025, 0.975], N * 3) / N
            print(f"  NIS {np.mean(nis):.2f} (m 3, band {band[0]:.2f}-{band[1]:.2f})")
        rmse = np.sqrt(np.mean(np.square(errors), axis=0))
        for entry, value in zip(psi.names, rmse, strict=True):
            print(f"  RMSE {entry:14s} {value:.3g}")


if __name__ == "__main__":
    main()
