"""Compiled kernels never run stale: numba's on-disk cache keyed on every source they inline.

Imported first by ``roller_gym`` (so installed before any kernel is defined). numba keys a
cached kernel on its own file only, while roller-gym's kernels inline functions
of other modules (the tasks' objectives, the reward vocabulary, the sines, the equations).
:class:`DigestLocator` gives each
kernel of ``roller_gym`` (and each kernel made for a task whose module lies elsewhere) a
source stamp that digests its own file, the files of the modules its code and closure name
(a task's module among them) and of every roller_gym module those reach through their
globals: editing any of them makes the next run recompile. Where
the package's folder is read-only, numba's own fall-backs (``NUMBA_CACHE_DIR``, then the
user-wide cache) still choose the folder.
"""

from __future__ import annotations

import hashlib
import inspect
import os
import sys
import types
from typing import Any

from numba.core import caching

__all__ = ["DigestLocator", "install", "sources"]

#: numba's cache implementation, whose list of locators is tried in order (its name before
#: numba 0.62 had an underscore).
_IMPL = getattr(caching, "CacheImpl", None) or caching._CacheImpl
#: The package whose kernels (and the modules they reach) are digested.
PACKAGE = "roller_gym"


def _module_of(value: Any) -> types.ModuleType | None:
    """The module that defines ``value`` (a module, function, dispatcher or class), if any."""
    if isinstance(value, types.ModuleType):
        return value
    func = getattr(value, "py_func", value)  # a numba dispatcher's Python function
    name = getattr(func, "__module__", None)
    return sys.modules.get(name) if isinstance(name, str) else None


def _reachable(func: Any, seen: set[str]) -> None:
    """Add to ``seen`` the modules a function reaches: its own, those of the globals its code
    names and of its closure's cells (a task's module), and, through their globals,
    roller_gym's modules, recursively."""
    roots = [_module_of(func)]
    code = getattr(func, "__code__", None)
    if code is not None:
        names, stack = set(), [code]
        while stack:  # the code and the code objects nested in it
            c = stack.pop()
            names.update(c.co_names)
            stack.extend(x for x in c.co_consts if isinstance(x, types.CodeType))
        found = getattr(func, "__globals__", {})
        roots += [_module_of(found[n]) for n in names if n in found]
    for cell in getattr(func, "__closure__", None) or ():
        try:
            roots.append(_module_of(cell.cell_contents))
        except ValueError:  # an empty cell
            continue
    for module in roots:
        _add_module(module, seen, root=True)


def _is_package(name: str) -> bool:
    return name == PACKAGE or name.startswith(PACKAGE + ".")


def _add_module(module: types.ModuleType | None, seen: set[str], root: bool) -> None:
    """Add a module (a root, or one of roller_gym's) and the roller_gym modules its globals
    reach; installed libraries and the standard library are left out."""
    if module is None or module.__name__ in seen or not getattr(module, "__file__", None):
        return
    if module.__name__.split(".")[0] in _OUTSIDE or not (root or _is_package(module.__name__)):
        return
    seen.add(module.__name__)
    for value in list(vars(module).values()):
        inner = _module_of(value)
        if inner is not None and inner is not module and _is_package(inner.__name__):
            _add_module(inner, seen, root=False)


#: Top-level packages whose sources are never digested (installed libraries: their versions
#: are numba's and Python's concern, and reading them would cost every import).
_OUTSIDE = frozenset(sys.stdlib_module_names) | {"numba", "numpy", "scipy", "llvmlite",
                                                 "gymnasium", "builtins"}


def sources(func: Any) -> tuple[str, ...]:
    """The source files a kernel's stamp digests (sorted): see the module docs."""
    seen: set[str] = set()
    _reachable(func, seen)
    files = {inspect.getfile(sys.modules[name]) for name in seen}
    return tuple(sorted(f for f in files if f.endswith(".py")))


def _digest(files: tuple[str, ...]) -> str:
    """One digest of the files' contents (each file's hash cached on its mtime and size)."""
    h = hashlib.sha256()
    for path in files:
        st = os.stat(path)
        h.update(path.encode() + caching._hash_source_file(path, st.st_mtime, st.st_size))
    return h.hexdigest()


def _ours(py_func: Any) -> bool:
    """Whether a function is one of roller_gym's kernels (or a kernel made for a task)."""
    return _is_package(getattr(py_func, "__module__", "") or "")


class DigestLocator(caching._CacheLocator):
    """numba's locator for a roller_gym kernel, with a source stamp that digests every source
    the kernel reaches (see the module docs); the cache folder is the one numba would use."""

    def __init__(self, inner: caching._CacheLocator, py_func: Any) -> None:
        self._inner = inner
        self._py_func = py_func

    def ensure_cache_path(self) -> None:
        self._inner.ensure_cache_path()

    def get_cache_path(self) -> str:
        return self._inner.get_cache_path()

    def get_disambiguator(self) -> str:
        return self._inner.get_disambiguator()

    def get_source_stamp(self) -> Any:
        return (self._inner.get_source_stamp(), _digest(sources(self._py_func)))

    @classmethod
    def from_function(cls, py_func: Any, py_file: str) -> DigestLocator | None:
        if not _ours(py_func):
            return None
        for locator_class in _IMPL._locator_classes:
            if locator_class is cls:
                continue
            inner = locator_class.from_function(py_func, py_file)
            if inner is not None:
                return cls(inner, py_func)
        return None


def install() -> None:
    """Put :class:`DigestLocator` first in numba's list of cache locators (once)."""
    classes = _IMPL._locator_classes
    if DigestLocator not in classes:
        classes.insert(0, DigestLocator)


install()
