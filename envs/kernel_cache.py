"""Compiled kernels never run stale: numba's on-disk cache keyed on every source they inline.

Imported first by ``roller_gym`` (so installed before any kernel is defined). numba keys a
cached kernel on its own file only, while roller-gym's kernels inline functions
of other modules (the tasks' objectives, the reward vocabulary, the sines, the equations).
:class:`DigestLocator` gives each
kernel of ``roller_gym`` (and each kernel made for a task whose module lies elsewhere) a
source stamp that digests every source file of the package and the module of a task its
closure names: editing any of them makes the next run recompile (all of the package's
kernels: a digest of what one kernel reaches would depend on the process's imports). Where
the package's folder is read-only, numba's own fall-backs (``NUMBA_CACHE_DIR``, then the
user-wide cache) still choose the folder.
"""

from __future__ import annotations

import hashlib
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


def _is_package(name: str) -> bool:
    return name == PACKAGE or name.startswith(PACKAGE + ".")


#: Top-level packages whose sources are never digested (installed libraries: their versions
#: are numba's and Python's concern).
_OUTSIDE = frozenset(sys.stdlib_module_names) | {"numba", "numpy", "scipy", "llvmlite",
                                                 "gymnasium", "builtins"}


def _package_files() -> tuple[str, ...]:
    """Every source file of the roller_gym package (its folder, recursively), sorted."""
    root = os.path.dirname(os.path.abspath(__file__))
    found = []
    for folder, _, names in os.walk(root):
        found += [os.path.join(folder, n) for n in names if n.endswith(".py")]
    return tuple(sorted(found))


def sources(func: Any) -> tuple[str, ...]:
    """The source files a kernel's stamp digests: every file of the roller_gym package, and
    the module of each of its closure's cells that lies outside it (a task's own module).
    The whole package rather than the modules a kernel reaches: what a module's globals
    reach depends on what the process imported before, and the stamp must not."""
    outside = set()
    for cell in getattr(func, "__closure__", None) or ():
        try:
            module = _module_of(cell.cell_contents)
        except ValueError:  # an empty cell
            continue
        name = getattr(module, "__name__", "") or ""
        if (module is not None and getattr(module, "__file__", None) and not _is_package(name)
                and name.split(".")[0] not in _OUTSIDE):
            outside.add(os.path.abspath(module.__file__))
    return _package_files() + tuple(sorted(outside))


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

    def __init__(self, inner: caching._CacheLocator, py_func: Any, py_file: str) -> None:
        self._inner = inner
        self._py_func = py_func
        self._py_file = py_file  # numba names it in its warning on a kernel it cannot cache

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
                return cls(inner, py_func, py_file)
        return None


def install() -> None:
    """Put :class:`DigestLocator` first in numba's list of cache locators (once)."""
    classes = _IMPL._locator_classes
    if DigestLocator not in classes:
        classes.insert(0, DigestLocator)


install()
