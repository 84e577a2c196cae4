"""
Simulation-based calibration of a model, from Python
====================================================

Is the posterior's uncertainty honest? Simulation-based calibration (SBC; Talts et al. 2018,
arXiv:1804.06788) answers it for the whole pipeline — prior, simulator, likelihood, sampler — on
synthetic truth. Each replicate draws parameters from the prior, simulates data with them, fits
the posterior and records the *rank* of the true value among ``L`` thinned posterior draws. If
the posterior is right the ranks are uniform on ``0..L`` (Talts et al., Theorem 1); a posterior
too narrow piles them at both ends, a biased one at one end.

This example runs a small SBC campaign with the library (what ``cassini-bayes sbc`` runs):
:class:`~cassini_bayes.analysis.sbc_models.ModelSpec` names the model and its sampler sizes,
:func:`~cassini_bayes.analysis.campaign.run_campaign` runs the replicates in batches (with
checkpoints in ``--out``: run it again with the same settings and finished batches are reused),
and :func:`~cassini_bayes.analysis.sbc.sbc_result` tests the ranks for uniformity: Pearson's
chi-square on binned ranks and the ECDF simultaneous-band test of Säilynoja et al. (2022), each
at a Bonferroni level so that a correct model falsely fails with probability at most ``--alpha``.

The default is the inertia model (idealised inertia posterior, three simulated one-axis RWA
slews, truth drawn from the posterior's own prior) with a small number of replicates: enough to
catch a grossly wrong posterior, not to prove a good one; ``cassini-bayes sbc`` runs hundreds.
``--model toy`` is a linear-Gaussian regression that checks the machinery in seconds.

Run ``python examples/sbc_check.py --help`` for the settings.
"""

import argparse
import tempfile

import numpy as np

from cassini_bayes.analysis.campaign import run_campaign
from cassini_bayes.analysis.sbc import sbc_result
from cassini_bayes.analysis.sbc_models import ModelSpec


def main(args):
    # The model and its sampler sizes (plain data, so a Dask worker could rebuild the same model).
    spec = ModelSpec.make(args.model, num_chains=args.chains, num_warmup=args.warmup,
                          num_draws=args.draws, thin=args.thin)

    # Replicate i uses the key fold_in(key(seed), i): the ranks depend on the seed only.
    with tempfile.TemporaryDirectory() as scratch:
        workdir = args.out or scratch
        campaign = run_campaign(spec, args.replicates, workdir, seed=args.seed,
                                batch_size=args.batch)

    ok = ~campaign.failed  # replicates whose fit produced finite draws
    result = sbc_result(campaign.names, campaign.rank[ok], campaign.n_draws,
                        alpha_family=args.alpha)

    print(f"SBC of the {args.model!r} model: {int(ok.sum())} replicates, ranks among "
          f"{campaign.n_draws} draws (failed {int(campaign.failed.sum())}, not converged "
          f"{int((~campaign.converged & ok).sum())})")
    print(f"{'parameter':10} {'chi2 p':>7} {'ECDF p':>7}  ranks")
    for j, name in enumerate(result.names):
        p = result.parameters[name]
        ranks = " ".join(str(int(r)) for r in np.asarray(result.ranks)[:, j])
        print(f"{name:10} {p.chi2.p_value:7.3f} {p.ecdf.p_value:7.3f}  {ranks}")
    verdict = "passed" if result.passed() else "FAILED"
    print(f"rank uniformity {verdict} (each parameter tested at alpha = {result.alpha:.3g}, "
          f"family-wise {result.alpha_family})")
    return result


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="A small simulation-based calibration check")
    parser.add_argument("--model", default="inertia", choices=["inertia", "thrust", "rwa4", "toy"],
                        help="model to calibrate")
    parser.add_argument("--replicates", type=int, default=20, help="number of replicates")
    parser.add_argument("--chains", type=int, default=2, help="NUTS chains per replicate")
    parser.add_argument("--warmup", type=int, default=300, help="warm-up iterations per chain")
    parser.add_argument("--draws", type=int, default=300, help="draws per chain before thinning")
    parser.add_argument("--thin", type=int, default=3, help="keep every thin-th draw")
    parser.add_argument("--batch", type=int, default=4, help="replicates per vectorised batch")
    parser.add_argument("--alpha", type=float, default=0.01,
                        help="family-wise false-failure rate of each uniformity test")
    parser.add_argument("--seed", type=int, default=0, help="root seed of the campaign")
    parser.add_argument("--out", default=None,
                        help="checkpoint directory, reused by a rerun (default: a temporary one)")
    args = parser.parse_args()
    main(args)
