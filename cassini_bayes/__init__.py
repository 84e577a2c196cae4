"""cassini_bayes: Bayesian uncertainty quantification of Cassini in-flight calibration.

Estimates the inertia tensor from reaction-wheel slews, the thrusters' force and pulse time
constants from wheel-biasing events, and the spin axis of the re-articulated wheel RWA4, as the
JPL papers did by least squares (kept here as baselines), but with calibrated posteriors.

The package computes in 64-bit: the conservation checks and least-squares recoveries it promises
(1e-9, 1e-8 relative) are beyond float32, so importing it turns on ``jax_enable_x64``.
"""

import jax

jax.config.update("jax_enable_x64", True)

__version__ = "0.1.0"

__all__ = ["__version__"]
