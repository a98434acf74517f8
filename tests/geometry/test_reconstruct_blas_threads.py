"""A blade reconstruction runs with one BLAS thread (``reconstruct.BLAS_THREADS``) and gives the
caller's limit back: its linear algebra is on short vectors, where more threads only spin, and
the guard's repair budget counts process CPU (docs/benchmarks.md, "A sparse edge pooled along
the span"). The first step inside is a stand-in that records the threads and stops the run."""

from __future__ import annotations

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

import steamtwin.geometry.frame as frame
import steamtwin.geometry.reconstruct as reconstruct


class _Seen(Exception):
    """Raised by the stand-in once it has recorded the threads."""


def _blas_threads() -> set[int]:
    return {pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"}


@pytest.fixture
def seen(monkeypatch) -> list[set[int]]:
    """BLAS thread counts inside the first step of each entry point."""
    recorded: list[set[int]] = []

    def first_step(*args, **kwargs):
        recorded.append(_blas_threads())
        raise _Seen

    monkeypatch.setattr(reconstruct, "segment_blade", first_step)
    monkeypatch.setattr(frame, "estimate_blade_frame", first_step)
    return recorded


@pytest.mark.parametrize("entry", [reconstruct.reconstruct_blade, frame.reconstruct_in_any_pose])
def test_reconstruction_runs_with_one_blas_thread(seen, entry) -> None:
    assert reconstruct.BLAS_THREADS == 1
    with threadpool_limits(limits=2, user_api="blas"):
        outside = _blas_threads()
        with pytest.raises(_Seen):
            entry(np.zeros((10, 3)))
        assert _blas_threads() == outside  # the caller's limit is back
    assert outside == {2}
    assert seen == [{1}]
