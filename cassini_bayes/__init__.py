"""cassini_bayes: Bayesian uncertainty quantification of Cassini in-flight calibration.

Estimates the inertia tensor from reaction-wheel slews, the thrusters' force and pulse time
constants from wheel-biasing events, and the spin axis of the re-articulated wheel RWA4, as the
JPL papers did by least squares (kept here as baselines), but with calibrated posteriors.

The package computes in 64-bit: the conservation checks and least-squares recoveries it promises
(1e-9, 1e-8 relative) are beyond float32, so importing it turns on ``jax_enable_x64``.

Importing it also turns on JAX's persistent compilation cache (a later process loads the compiled
programs instead of compiling them again): in ``~/.cache/cassini-bayes/jax`` (or
``$XDG_CACHE_HOME/cassini-bayes/jax``), moved or switched off with the environment variable
``CASSINI_BAYES_JAX_CACHE=DIR|off`` (:mod:`cassini_bayes._jax_cache`, docs/performance.md).
"""

import jax

from cassini_bayes import _jax_cache

jax.config.update("jax_enable_x64", True)
_jax_cache.enable()  # before any JAX array exists

__version__ = "0.1.0"

__all__ = ["__version__"]
