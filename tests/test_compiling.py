"""The notice of a long first compile (roller_gym.physics.compiling), with a clock that
fires at once: said once per kernel, for the package's outermost compiles only."""

from __future__ import annotations

import numba
import pytest
from numba.core import event
from roller_gym.physics import compiling


def _dispatcher(module: str):
    def kernel(x):
        return x + 1.0

    kernel.__module__ = module
    return numba.njit(kernel)


class _AtOnce:
    """threading.Timer's face, firing when started."""

    def __init__(self, _delay: float, function, args) -> None:
        self.function, self.args, self.daemon = function, args, False

    def start(self) -> None:
        self.function(*self.args)

    def cancel(self) -> None:
        pass


def _compile(notice: compiling._Notice, *dispatchers) -> None:
    """Events of nested compiles: the first dispatcher outermost."""
    for d in dispatchers:
        notice.on_start(event.Event("numba:compile", event.EventStatus.START,
                                    data={"dispatcher": d, "args": ()}))
    for d in reversed(dispatchers):
        notice.on_end(event.Event("numba:compile", event.EventStatus.END,
                                  data={"dispatcher": d, "args": ()}))


def test_a_long_compile_is_announced_once(capsys: pytest.CaptureFixture[str],
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(compiling.threading, "Timer", _AtOnce)
    notice = compiling._Notice()
    ours, inner = _dispatcher("roller_gym.probe"), _dispatcher("roller_gym.inner")
    _compile(notice, ours, inner)
    _compile(notice, ours)  # a second compile of the same kernel: said already
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1
    assert "roller_gym.probe" in lines[0] and "first use" in lines[0]
    assert "roller_gym.inner" not in lines[0]  # nested: part of the outer one's compile


def test_other_packages_compiles_are_not_announced(capsys: pytest.CaptureFixture[str],
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(compiling.threading, "Timer", _AtOnce)
    notice = compiling._Notice()
    _compile(notice, _dispatcher("someone_else"), _dispatcher("roller_gym.probe"))
    assert capsys.readouterr().err == ""


def test_a_short_compile_is_not_announced(capsys: pytest.CaptureFixture[str]) -> None:
    notice = compiling._Notice()  # the real clock: the compile ends long before it fires
    _compile(notice, _dispatcher("roller_gym.probe"))
    assert capsys.readouterr().err == ""
