"""Posteriors an experiment reads from the fits of others: the budgets' inputs.

A setting naming a posterior is a run directory, ``""`` (none) or ``"auto"``: the fit the
experiment ``AUTO_RUNS`` names, written earlier in the same ``reproduce`` run (experiments run in
order into sibling folders; :func:`find_posterior` looks beside the experiment's own folder). Under
``cassini-bayes experiment`` there is no sibling and ``"auto"`` finds nothing: the budget lines then
keep the papers' values.
"""

from __future__ import annotations

from pathlib import Path

from cassini_bayes.errors import InputError

__all__ = ["AUTO_RUNS", "find_posterior"]

# which -> (fit sub-run of an earlier experiment, posterior kind)
AUTO_RUNS = {
    "inertia": ("inertia_table1/fits/post_probe", "inertia"),
    "thrust": ("thrust_table2/fits/pooled", "thrust"),
    "rwa4_rcs": ("rwa4_rcs_campaign/fits/run00", "rwa4"),
    "rwa4_rwa": ("rwa4_rwa_campaign/fits/run00", "rwa4"),
}


def find_posterior(value: str, which: str, setting: str, ctx):
    """The :class:`~cassini_bayes.analysis.posterior_budgets.Posterior` a setting names, or
    ``None`` (``""``, or ``"auto"`` with no earlier fit); an error naming ``setting`` when a
    named run directory cannot be read."""
    from cassini_bayes.analysis.posterior_budgets import load_posterior

    if value == "":
        return None
    sub, kind = AUTO_RUNS[which]
    if value == "auto":
        path = Path(ctx.workdir).parent / sub
        if not (path / "posterior.nc").is_file():
            return None
    else:
        path = Path(value)
    try:
        post = load_posterior(path, kind, option=f"settings.{setting}")
    except InputError as e:
        raise ctx.error(str(e)) from None
    if kind == "rwa4" and post.method is None:
        post = post._replace(method=which.split("_")[1])
    if value == "auto":  # the temporary folder is renamed: name the fit relative to this run
        post = post._replace(source=f"../{sub}")
    return post
