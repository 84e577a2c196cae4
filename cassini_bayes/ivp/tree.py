"""The Inertial Vector Table as a tree, and targets as signed paths through it (Lee §3.3, Fig 8).

Each entry is a vector from a *base* to a *head* (named points: bodies, the spacecraft), modelled
by a conic or a list of Chebyshev segments, with the time interval over which the model holds.
Every point has at most one entry ending at it (its parent), so the entries form a tree and
two points are joined by exactly one path. A target (``base → head``) is evaluated by adding the
entries along that path, each with the sign of its direction along the path: during Tour the
Earth from the spacecraft is ``−(Saturn→spacecraft) − (Sun→Saturn) + (Sun→Earth)``; during a
Titan flyby the spacecraft hangs from Titan instead of Saturn, and the path gains Titan→Saturn.

A time outside an entry's interval is an :class:`~cassini_bayes.errors.InputError` naming the
entry: a model is never extrapolated.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Union

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from cassini_bayes.errors import InputError
from cassini_bayes.ivp._checks import check_finite, check_interval
from cassini_bayes.ivp.chebyshev import ChebyshevSegments
from cassini_bayes.ivp.conic import Conic

__all__ = ["TreeEntry", "VectorTree"]

Model = Union[Conic, ChebyshevSegments]


@dataclass(frozen=True)
class TreeEntry:
    """One vector of the table: from ``base`` to ``head``, modelled by ``model`` (a
    :class:`~cassini_bayes.ivp.conic.Conic` or
    :class:`~cassini_bayes.ivp.chebyshev.ChebyshevSegments`) over ``[t_start_s, t_end_s]``
    (s; for segments, default their span, which must cover it)."""

    base: str
    head: str
    model: Model
    t_start_s: float | None = None
    t_end_s: float | None = None

    def __post_init__(self):
        for what in ("base", "head"):
            name = getattr(self, what)
            if not isinstance(name, str) or not name.strip():
                raise InputError(f"an entry's {what} must be a non-empty name, got {name!r}")
        if self.base == self.head:
            raise InputError(f"entry {self.name}: base and head are the same point")
        if not isinstance(self.model, (Conic, ChebyshevSegments)):
            raise InputError(f"entry {self.name}: the model must be a Conic or "
                             f"ChebyshevSegments, got {type(self.model).__name__}")
        if isinstance(self.model, ChebyshevSegments):
            lo, hi = self.model.t_start_s, self.model.t_end_s
            t0 = lo if self.t_start_s is None else float(self.t_start_s)
            t1 = hi if self.t_end_s is None else float(self.t_end_s)
            if t0 < lo or t1 > hi:
                raise InputError(f"entry {self.name}: interval [{t0:g}, {t1:g}] s reaches "
                                 f"beyond its segments [{lo:g}, {hi:g}] s")
        elif self.t_start_s is None or self.t_end_s is None:
            raise InputError(f"entry {self.name}: a conic needs its validity interval "
                             "(t_start_s, t_end_s)")
        else:
            t0, t1 = float(self.t_start_s), float(self.t_end_s)
        check_interval(t0, t1, f"entry {self.name}")
        object.__setattr__(self, "t_start_s", t0)
        object.__setattr__(self, "t_end_s", t1)

    @property
    def name(self) -> str:
        return f"'{self.base}->{self.head}'"

    def vector(self, t_s) -> Array:
        """The base→head vector at times ``t_s`` (s), shape ``t_s.shape + (3,)``; times outside
        the interval are refused (concrete times only: traced ones are not checked)."""
        if not isinstance(t_s, jax.core.Tracer):
            t = np.asarray(t_s, float)
            check_finite(t, "t")
            outside = (t < self.t_start_s) | (t > self.t_end_s)
            if outside.any():
                bad = float(t[outside].flat[0])
                raise InputError(f"entry {self.name} is valid over [{self.t_start_s:g}, "
                                 f"{self.t_end_s:g}] s; t = {bad:g} s is outside it: add an "
                                 "entry that covers it")
        return self.model.position(t_s)


class VectorTree:
    """Named vectors related in a tree (Lee's Inertial Vector Table) and the targets through it.

    ``VectorTree(entries)`` checks that every point has at most one parent and that there is no
    loop. :meth:`path` gives the signed entries from one point to another, :meth:`vector` their
    sum, :meth:`with_entry` a tree with one point re-hung (a new parent or a new model).
    """

    def __init__(self, entries: Iterable[TreeEntry]):
        parent: dict[str, TreeEntry] = {}
        for e in entries:
            if not isinstance(e, TreeEntry):
                raise InputError(f"expected TreeEntry items, got {type(e).__name__}")
            if e.head in parent:
                raise InputError(f"two entries end at '{e.head}' ({parent[e.head].name} and "
                                 f"{e.name}): in a tree each point has one parent; use "
                                 "with_entry to replace one")
            parent[e.head] = e
        for start in parent:                     # walk up from every point: no loops
            seen, node = {start}, start
            while node in parent:
                node = parent[node].base
                if node in seen:
                    raise InputError(f"the entries make a loop through '{node}': a vector "
                                     "tree has exactly one path between two points")
                seen.add(node)
        self._parent = parent

    @property
    def entries(self) -> tuple[TreeEntry, ...]:
        return tuple(self._parent.values())

    @property
    def points(self) -> tuple[str, ...]:
        names = {e.head for e in self.entries} | {e.base for e in self.entries}
        return tuple(sorted(names))

    def with_entry(self, entry: TreeEntry) -> "VectorTree":
        """This tree with ``entry`` replacing the one ending at ``entry.head`` (or added)."""
        return VectorTree([e for e in self.entries if e.head != entry.head] + [entry])

    def _ancestors(self, point: str) -> list[str]:
        chain = [point]
        while chain[-1] in self._parent:
            chain.append(self._parent[chain[-1]].base)
        return chain

    def path(self, base: str, head: str) -> list[tuple[TreeEntry, int]]:
        """The entries from ``base`` to ``head``, each with ``+1`` when it points along the path
        and ``−1`` against it."""
        for p in (base, head):
            if p not in self.points:
                raise InputError(f"'{p}' is not a point of the vector tree; points: "
                                 f"{', '.join(self.points)}")
        up_from_base, up_from_head = self._ancestors(base), self._ancestors(head)
        common = next((p for p in up_from_base if p in set(up_from_head)), None)
        if common is None:
            raise InputError(f"no path from '{base}' to '{head}': they are in separate trees")
        down = up_from_base[:up_from_base.index(common)]
        up = up_from_head[:up_from_head.index(common)]
        return [(self._parent[p], -1) for p in down] + [(self._parent[p], +1)
                                                         for p in reversed(up)]

    def vector(self, base: str, head: str, t_s) -> Array:
        """The ``base → head`` vector at times ``t_s`` (s): the signed sum along :meth:`path`
        (Lee §3.3); shape ``t_s.shape + (3,)``."""
        t = jnp.asarray(t_s, float)
        total = jnp.zeros(t.shape + (3,))
        for entry, sign in self.path(base, head):
            total = total + sign * entry.vector(t_s)
        return total
