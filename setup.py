"""The package's long description: README.md with its relative links made to work off-site.

Everything else about the package is in pyproject.toml. A package index (PyPI) shows the
long description away from the repository, where README.md's relative links
(``docs/PHYSICS.md``) lead nowhere. At build time this file rewrites each of them:

* if ``[tool.roller_gym.readme] base-url`` is set in pyproject.toml (the URL under which
  the repository's files are browsable, e.g. ``https://github.com/ORG/roller-gym/blob/v0.1.0/``;
  ``image-base-url`` for images, e.g. ``.../raw/v0.1.0/``, defaults to it), into an
  absolute link to that file;
* otherwise into plain text naming the file, and a closing note says where those files are:
  the repository and the source distribution (MANIFEST.in ships ``docs/``), and how to make
  one while roller-gym is not on PyPI.

Links with a scheme (``https:``), anchors (``#...``) and code are left as they are.
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path
from urllib.parse import urljoin

from setuptools import setup

HERE = Path(__file__).resolve().parent

# Fenced code, code spans and links, in one pass so that code is never rewritten (a link's
# text may itself be a code span: [`docs/X.md`](docs/X.md)).
_TOKEN = re.compile(
    r"(?P<fence>^(?P<f>```|~~~).*?^(?P=f))"
    r"|(?P<code>(?P<ticks>`+)(?:(?!(?P=ticks)).)+?(?P=ticks))"
    r"|(?P<bang>!?)\[(?P<text>(?:[^\[\]]|\[[^\]]*\])*)\]\(\s*(?P<target>[^)\s]+)\s*\)",
    re.M | re.S,
)
_SCHEME = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:|^#|^//")
#: Appended when links became file names: where those files are.
NOTE = (
    "*The files named above ({files}) are in roller-gym's repository and in its source "
    "distribution, which `python -m build --sdist` makes in a clone (`pip install build` "
    "first). Once roller-gym is published on PyPI, `pip download --no-deps --no-binary :all: "
    "roller-gym` will fetch it.*"
)


def _rewrite(token: re.Match[str], base: str, image_base: str, named: list[str]) -> str:
    target = token.group("target")
    if target is None or _SCHEME.match(target):
        return token.group(0)
    bang, text = token.group("bang"), token.group("text")
    path = target.removeprefix("./")
    named.append(path.split("#")[0])
    if base:
        return f"{bang}[{text}]({urljoin(image_base if bang else base, path)})"
    if text.strip("`") == path.split("#")[0]:
        return text
    return f"{text} (`{path}`)"


def long_description(readme: str, base: str = "", image_base: str = "") -> str:
    """``readme`` with its relative links absolute under ``base`` (or plain text if none)."""
    if base and not base.endswith("/"):
        base += "/"
    image_base = image_base or base
    if image_base and not image_base.endswith("/"):
        image_base += "/"
    named: list[str] = []
    out = _TOKEN.sub(lambda token: _rewrite(token, base, image_base, named), readme)
    if named and not base:
        files = ", ".join(f"`{name}`" for name in dict.fromkeys(named))
        out = out.rstrip("\n") + "\n\n" + NOTE.format(files=files) + "\n"
    return out


def _settings() -> dict[str, str]:
    pyproject = tomllib.loads((HERE / "pyproject.toml").read_text(encoding="utf-8"))
    return pyproject.get("tool", {}).get("roller_gym", {}).get("readme", {})


if __name__ == "__main__":
    settings = _settings()
    setup(
        long_description=long_description(
            (HERE / "README.md").read_text(encoding="utf-8"),
            settings.get("base-url", ""),
            settings.get("image-base-url", ""),
        ),
        long_description_content_type="text/markdown",
    )
