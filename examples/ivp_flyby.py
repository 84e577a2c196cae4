"""
Pointing through a Titan flyby: conics, Chebyshev segments and the vector tree
==============================================================================

Cassini's inertial vector propagator (Lee §3.3) keeps the vectors the spacecraft points along
as conics (seven numbers, propagated by Goodyear's universal-variable method, Eqs 12-14) where a
single body dominates, and as Chebyshev polynomial segments (Eqs 15-18, order ≤ 12) where it
does not, such as a close Titan flyby; a target is a signed path through the tree of vectors
(Fig 8: spacecraft → Titan → Saturn → Sun → Earth).

This example integrates the bodies around a Titan flyby (``cassini_bayes.ivp.nbody``), writes
the spacecraft's position relative to Titan every 60 s as a trajectory file, fits segments to
it with :func:`cassini_bayes.fit_trajectory` (what ``cassini-bayes ivp fit`` runs), hangs them in
a :class:`cassini_bayes.VectorTree` beside conics for Titan, Saturn and the Earth, and prints how
far the Earth and Saturn directions from the spacecraft are from the integrated truth.

Run ``python examples/ivp_flyby.py --help`` for the settings.
"""

import argparse
import tempfile
from pathlib import Path

import numpy as np

import cassini_bayes as cb
from cassini_bayes.ivp import TreeEntry, fit_conic
from cassini_bayes.ivp.nbody import GM, Flyby, integrate_flyby
from cassini_bayes.ivp.segmenter import angle_between_vectors
from cassini_bayes.ivp.trajectory import Trajectory, write_trajectory

DAY = 86400.0


def main(args):
    half = 0.5 * args.days * DAY
    sol = integrate_flyby(-half, half, Flyby(altitude_m=args.altitude_km * 1e3))

    # The spacecraft relative to Titan, sampled every 60 s, as a trajectory file.
    t = np.arange(-half, half + 1.0, 60.0)
    with tempfile.TemporaryDirectory() as scratch:
        path = Path(scratch) / "titan_to_spacecraft.csv"
        write_trajectory(path, Trajectory(t, sol.relative("titan", "spacecraft")(t)))
        fit = cb.fit_trajectory(path, requirement_urad=args.requirement_urad, mu=GM["titan"])
        out = fit.save(args.out, force=True)
    s = fit.summary()
    print(f"{s['n_segments']} Chebyshev segments over {args.days:g} days, {s['n_coefficients']} "
          f"numbers; largest angle {s['max_error_samples_urad']:.1f} µrad at the samples "
          f"(requirement {args.requirement_urad:g}); one conic about Titan: "
          f"{s['conic']['max_error_urad']:.3g} µrad")
    for k, seg in enumerate(s["segments"]):
        print(f"  segment {k + 1}: {(seg['t_end_s'] - seg['t_start_s']) / 3600:8.2f} h, order "
              f"{seg['order']:2d}, {seg['coefficients']} numbers, {seg['max_error_urad']:.1f} µrad")

    # The vector tree of Fig 8 during the flyby: conics for the bodies (their seven numbers fitted
    # over the span: Saturn's J2 makes Titan's osculating conic drift off within days), the
    # segments for the spacecraft.
    entries = [TreeEntry("titan", "spacecraft", fit.fit.segments)]
    for base, head, mu in (("sun", "saturn", GM["sun"] + GM["saturn"] + GM["titan"]),
                           ("sun", "earth", GM["sun"] + GM["earth"]),
                           ("saturn", "titan", GM["saturn"] + GM["titan"])):
        r0, v0 = sol.state(head, 0.0, base)
        conic = fit_conic(sol.relative(base, head), -half, half, r0=r0, v0=v0, mu=mu, t0_s=0.0)
        entries.append(TreeEntry(base, head, conic, -half, half))
    tree = cb.VectorTree(entries)
    grid = np.linspace(-half, half, 4001)
    for head in ("earth", "saturn"):
        path_names = " → ".join(["spacecraft"] + [e.base if s < 0 else e.head
                                                 for e, s in tree.path("spacecraft", head)])
        err = angle_between_vectors(np.asarray(tree.vector("spacecraft", head, grid)),
                                    sol.relative("spacecraft", head)(grid))
        print(f"target {path_names}: largest angle to the truth {err.max() * 1e6:.2f} µrad")

    # One conic by Goodyear's method: Titan about Saturn a day later.
    r0, v0 = sol.state("titan", 0.0, "saturn")
    r1, _ = cb.propagate_conic(r0, v0, GM["saturn"] + GM["titan"], DAY)
    truth = sol.relative("saturn", "titan")(np.array([DAY]))[0]
    print(f"Titan one day on as a conic: {angle_between_vectors(np.asarray(r1), truth) * 1e6:.2f}"
          " µrad from the integrated Titan")
    print(f"run directory: {out}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="Conics, Chebyshev segments and the vector "
                                                 "tree through a Titan flyby (Lee §3.3)")
    parser.add_argument("--days", type=float, default=14.0, help="span centred on the flyby")
    parser.add_argument("--altitude-km", type=float, default=1000.0,
                        help="closest approach above Titan's surface, km")
    parser.add_argument("--requirement-urad", type=float, default=40.0,
                        help="largest angle between fitted and true vector, µrad")
    parser.add_argument("--out", default="runs/example_ivp_flyby", help="run directory")
    # 64-bit JAX and the compilation cache: the public functions set them up themselves, but
    # this example also calls the package's modules directly
    cb.setup_jax()
    main(parser.parse_args())
