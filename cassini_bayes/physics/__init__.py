"""Pure JAX physics: momentum model, impulse model, thruster pulse response, dynamics.

Nothing here imports NumPyro, ArviZ, matplotlib or the CLI (checked by import-linter).
"""
