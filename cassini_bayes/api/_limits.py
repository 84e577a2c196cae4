"""The ranges of the fit functions' seeds, chains and draws, and the RWA4 fits' default target
acceptance: what the command line declares in its options.

Apart from :mod:`cassini_bayes.api._inputs` and the fit modules so that the command line can
declare its options without importing the readers, the models or JAX.
"""

# jax.random.key takes a signed 64-bit seed; the package takes its non-negative half
SEED_MAX = 2**63 - 1
# beyond these a fit runs out of memory or time before it says anything (16 chains already
# oversubscribe a 16-core machine; 10⁶ draws of a fit take hours)
MAX_CHAINS = 64
MAX_DRAWS = 1_000_000

RWA4_TARGET_ACCEPT = 0.95
"""The RWA4 fits' default NUTS target acceptance (the other fits': 0.9): at 0.9 an open-world
RWA4 fit can diverge where at 0.95 none did, at the same coverage (docs/robust/open_world.md,
"At the command line's defaults")."""
