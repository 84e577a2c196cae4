"""Memory mappings of compiled programs are released between a campaign's replicates."""

from __future__ import annotations

from pathlib import Path

import jax
import jax.numpy as jnp
import pytest

from cassini_bayes._devices import release_compiled_programs


@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="needs Linux's /proc")
def test_compiled_programs_are_dropped_only_past_the_share_of_the_mapping_limit():
    """Below the share nothing is dropped; past it (share 0) JAX's in-memory programs are
    cleared, so the next call compiles (or loads from the cache) again."""
    f = jax.jit(lambda x: jnp.sin(x) * 2.0)
    f(jnp.ones(3))
    assert f._cache_size() == 1
    assert not release_compiled_programs(share=1.0)
    assert f._cache_size() == 1
    assert release_compiled_programs(share=0.0)
    assert f._cache_size() == 0
    assert float(f(jnp.zeros(3)).sum()) == 0.0
