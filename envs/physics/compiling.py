"""A line on stderr where compiling a kernel for its first use takes a while.

numba compiles roller_gym's kernels on their first call in a process whose cache lacks them
and caches them on disk, so the next process loads them instead. :func:`install` (run on
importing :mod:`roller_gym.physics`) listens to numba's compile events: where compiling one
of the package's kernels (and what it calls) is still running after :data:`NOTICE_AFTER`
seconds, it says once on stderr what is being compiled and where it will be cached. Nothing
is printed for a kernel loaded from the cache, nor for a compile that ends sooner.

:data:`inlined` is how the small functions the kernels call are compiled (what costs least
to compile for the same machine code).
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable
from types import SimpleNamespace

from numba.core import event, sigutils
from numba.core.ccallback import CFunc
from numba.extending import register_jitable

#: Seconds a compile runs before its notice is printed.
NOTICE_AFTER = 2.0
#: The packages whose compiles are announced (their functions' ``__module__`` prefixes).
PACKAGES = ("roller_gym.",)


def _cache_path(dispatcher) -> str | None:
    """Where numba caches ``dispatcher`` (None if it is not cached)."""
    try:
        return dispatcher.stats.cache_path
    except AttributeError:
        return None


class _Notice(event.Listener):
    """Times the outermost compile of each thread; prints its notice past NOTICE_AFTER."""

    def __init__(self) -> None:
        self._local = threading.local()
        self._said: set[str] = set()
        self._lock = threading.Lock()

    def on_start(self, ev: event.Event) -> None:
        depth = getattr(self._local, "depth", 0)
        self._local.depth = depth + 1
        if depth:
            return
        dispatcher = ev.data["dispatcher"]
        func = getattr(dispatcher, "py_func", None)
        module = getattr(func, "__module__", "") or ""
        if not module.startswith(PACKAGES):
            self._local.timer = None
            return
        name = f"{module}.{func.__qualname__}"
        timer = threading.Timer(NOTICE_AFTER, self._say, (name, _cache_path(dispatcher)))
        timer.daemon = True
        self._local.timer = timer
        timer.start()

    def on_end(self, ev: event.Event) -> None:
        self._local.depth -= 1
        if self._local.depth == 0 and getattr(self._local, "timer", None) is not None:
            self._local.timer.cancel()
            self._local.timer = None

    def _say(self, name: str, cache: str | None) -> None:
        with self._lock:
            if name in self._said:
                return
            self._said.add(name)
        where = (f"numba caches it in {cache} for the next process" if cache
                 else "numba does not cache it")
        print(f"roller_gym: compiling {name} for its first use (once: {where}) ...",
              file=sys.stderr, flush=True)


_LISTENER: _Notice | None = None


def install() -> None:
    """Start announcing long compiles (once per process; later calls do nothing)."""
    global _LISTENER
    if _LISTENER is None:
        _LISTENER = _Notice()
        event.register("numba:compile", _LISTENER)


#: The options of the small compiled functions the kernels call (the equations, the sines,
#: the reward terms): each is compiled once per signature and inlined by LLVM where it is
#: called (``forceinline``), so that the loops that call it keep no call and run in SIMD
#: lanes. numba's own inlining (``inline="always"``) would type the inlined body again at
#: every call site, nested: that made the first compile of ``contact_state`` 4× as long (72 s
#: against 18 s on one machine under the same load), and the single environment's first step
#: 2× (803 s against 410 s under a load of 9 on 2 cores), for the same results.
INLINED_OPTIONS = {"nogil": True, "forceinline": True}
#: ``register_jitable`` with :data:`INLINED_OPTIONS`: the decorator of those functions.
inlined = register_jitable(**INLINED_OPTIONS)


def named(module: str, name: str, function: Callable) -> Callable:
    """``function`` (a plain function calling compiled ones) as module ``module``'s attribute
    ``name``, compiled as :data:`inlined` into each kernel that calls it: what a kernel made
    by a factory calls in place of another such kernel. numba keys a cached kernel made by a
    factory on its closure's contents, pickled: a compiled function there pickles differently
    in every process (the kernel is never loaded from the cache), a function its module names
    pickles by that name."""
    function.__name__ = function.__qualname__ = name
    function.__module__ = module
    setattr(sys.modules[module], name, function)
    return inlined(function)


class _CFunction(CFunc):
    """A ``numba.cfunc`` whose compile (not its load from the cache) is announced as a
    kernel's is: it reads as a dispatcher to :class:`_Notice`."""

    @property
    def py_func(self) -> Callable:
        return self._pyfunc

    @property
    def stats(self) -> SimpleNamespace:
        return SimpleNamespace(cache_path=getattr(self._cache, "_cache_path", None))

    def _compile_uncached(self):
        data = {"dispatcher": self, "args": self._sig.args, "return_type": self._sig.return_type}
        with event.trigger_event("numba:compile", data=data):
            return super()._compile_uncached()


def c_function(function: Callable, signature: object, **options: object) -> CFunc:
    """``function`` compiled as a C function of ``signature`` (``numba.cfunc``, with
    ``options``), cached on disk and loaded from there by the next process; a compile that
    takes a while is announced on stderr as a kernel's is."""
    compiled = _CFunction(function, sigutils.normalize_signature(signature), locals={},
                          options=options)
    compiled.enable_caching()
    compiled.compile()
    return compiled
