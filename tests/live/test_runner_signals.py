"""stop_on_signals: SIGTERM (and SIGINT) set the event that stops a command-line service."""

from __future__ import annotations

import asyncio
import os
import signal
import sys

import pytest

from steamtwin.live.runner import stop_on_signals


@pytest.mark.skipif(sys.platform == "win32", reason="no loop signal handlers on Windows")
def test_sigterm_sets_the_stop_event():
    async def main() -> bool:
        stop = stop_on_signals()
        assert not stop.is_set()
        # never SIGTERM the test process itself unless the loop took the signal over (without
        # the handler the signal would end the worker instead of failing this test)
        assert signal.getsignal(signal.SIGTERM) not in (signal.SIG_DFL, signal.SIG_IGN, None)
        os.kill(os.getpid(), signal.SIGTERM)
        await asyncio.wait_for(stop.wait(), timeout=5.0)
        asyncio.get_running_loop().remove_signal_handler(signal.SIGTERM)
        asyncio.get_running_loop().remove_signal_handler(signal.SIGINT)
        return stop.is_set()

    assert asyncio.run(main())
