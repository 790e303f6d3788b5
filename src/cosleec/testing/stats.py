"""Summary statistics shared by the benchmarks and timing-aware tests."""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["percentile"]


def percentile(xs: Sequence[float], p: float) -> float:
    """The ``p``-th percentile (0-100) of ``xs`` by the nearest-rank method on sorted data.

    Use it for p50/p99 latencies: it returns an observed value, never an interpolation.
    """
    if not xs:
        raise ValueError("percentile of no values")
    s = sorted(xs)
    return s[min(len(s) - 1, round(p / 100 * (len(s) - 1)))]
