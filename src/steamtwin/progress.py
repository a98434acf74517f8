"""The one progress-callback signature of steamtwin's long-running calls.

Every public function or method that takes ``progress`` calls it as
``progress(fraction, message)``: ``fraction`` is the share of the work done, a float in [0, 1]
that never decreases within one call, and ``message`` a short text of the current step ("GA
generation 12/200", "snapshot 5/32"), possibly empty. The CLI turns it into a rich progress bar;
a notebook user can pass ``lambda f, m: print(f"{f:.0%} {m}")``.

Seeds follow scikit-learn's habit the same way: every public call that draws random numbers takes
``random_state`` (an int, or ``None`` for fresh entropy where the call allows it).
"""

from __future__ import annotations

from collections.abc import Callable

__all__ = ["ProgressCallback", "scaled"]

ProgressCallback = Callable[[float, str], None]


def scaled(progress: ProgressCallback | None, start: float, stop: float,
           prefix: str = "") -> ProgressCallback | None:
    """A callback that maps a sub-step's [0, 1] onto ``[start, stop]`` of ``progress``.

    ``prefix`` is put in front of the sub-step's message ("reconstruct: " …). Returns ``None``
    when ``progress`` is ``None``, so callers can pass the result on unconditionally.
    """
    if progress is None:
        return None
    if not 0.0 <= start <= stop <= 1.0:
        raise ValueError(f"progress range [{start}, {stop}] must lie within [0, 1]")

    def sub(fraction: float, message: str = "") -> None:
        share = min(max(float(fraction), 0.0), 1.0)
        progress(start + (stop - start) * share, prefix + message)

    return sub
