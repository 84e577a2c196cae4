"""The checks' JAX work as three programs: called eagerly on NumPy arrays, every frames function
is a few one-operation programs, each loaded (or compiled) in every process.
"""

from __future__ import annotations

import jax

from cassini_bayes.frames import dcm, quat_conjugate, quat_multiply, quat_to_rotvec

_rotvecs_between = jax.jit(lambda qa, qb: quat_to_rotvec(quat_multiply(qb, quat_conjugate(qa))))
_conjugate = jax.jit(quat_conjugate)
_dcm = jax.jit(dcm)
