"""The documentation's links resolve in every clone.

Every relative link and image of ``README.md`` and ``docs/*.md`` (Markdown ``[text](target)``
and ``![alt](target)``, HTML ``<img src>`` and ``<a href>``) must point to a file tracked by
git (``git ls-files``): a file that exists only on one machine, or that ``.gitignore`` hides,
is broken for everyone else. An anchor (``#heading``) into a Markdown file must name one of
its headings. Links with a scheme (``https:``, ``mailto:``) are not checked.
"""

from __future__ import annotations

import re
import subprocess
import unicodedata
from pathlib import Path, PurePosixPath

import pytest

ROOT = Path(__file__).resolve().parents[1]

_FENCE = re.compile(r"^(```|~~~).*?^\1", re.M | re.S)
_CODE_SPAN = re.compile(r"(`+)(?:(?!\1).)+?\1", re.S)
_MD_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*(<[^>]*>|[^)\s]*)(?:\s+[\"'(][^)]*)?\)")
_HTML_LINK = re.compile(r"<(?:img|a)\b[^>]*?\b(?:src|href)\s*=\s*[\"']([^\"']*)[\"']", re.I)
_SCHEME = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")


def links(markdown: str) -> list[str]:
    """The targets of every link and image, code blocks and code spans left out."""
    text = _FENCE.sub("", markdown)
    text = _CODE_SPAN.sub("code", text)
    targets = [m.group(1).strip("<>") for m in _MD_LINK.finditer(text)]
    return targets + _HTML_LINK.findall(text)


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"`|\*\*?|__?", "", heading.strip()).lower()
    kept = "".join(
        ch for ch in text
        if ch in " -_" or unicodedata.category(ch)[0] in "LN"
    )
    return kept.replace(" ", "-")


def anchors(markdown: str) -> set[str]:
    """The anchors of a Markdown file's headings (repeats numbered -1, -2, ... as GitHub does)."""
    seen: dict[str, int] = {}
    out = set()
    for heading in re.findall(r"^#{1,6}\s+(.+?)\s*#*\s*$", _FENCE.sub("", markdown), re.M):
        base = slug(heading)
        n = seen.get(base, 0)
        seen[base] = n + 1
        out.add(base if n == 0 else f"{base}-{n}")
    return out


def broken_links(page: PurePosixPath, markdown: str, tracked: set[str],
                 read: dict[str, str]) -> list[str]:
    """The links of ``page`` (a path relative to the repository) that do not resolve.

    ``tracked``: the repository's files; ``read``: the text of the Markdown files, by path.
    """
    folders = {str(p) for f in tracked for p in PurePosixPath(f).parents}
    problems = []
    for target in links(markdown):
        if not target or _SCHEME.match(target) or target.startswith("//"):
            continue
        path, _, anchor = target.partition("#")
        if path.startswith("/"):
            problems.append(f"{target}: absolute path; use a path relative to {page}")
            continue
        resolved = page.parent / path if path else page
        parts: list[str] = []
        for part in resolved.parts:
            if part == "..":
                if not parts:
                    parts = [".."]
                    break
                parts.pop()
            elif part != ".":
                parts.append(part)
        name = "/".join(parts)
        if name.startswith(".."):
            problems.append(f"{target}: outside the repository")
        elif name not in tracked and name.rstrip("/") not in folders:
            problems.append(f"{target}: {name} is not tracked by git")
        elif anchor and name.endswith(".md") and anchor not in anchors(read.get(name, "")):
            problems.append(f"{target}: {name} has no heading with the anchor #{anchor}")
    return problems


def tracked_files() -> set[str]:
    try:
        out = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True,
                             check=True)
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git work tree (an unpacked source distribution?)")
    return set(out.stdout.decode().split("\0")) - {""}


PAGES = ["README.md", *sorted(f"docs/{p.name}" for p in (ROOT / "docs").glob("*.md"))]


@pytest.mark.parametrize("page", PAGES)
def test_every_relative_link_points_to_a_tracked_file(page: str) -> None:
    tracked = tracked_files()
    assert page in tracked, f"{page} is not tracked by git"
    read = {f: (ROOT / f).read_text() for f in tracked if f.endswith(".md")}
    problems = broken_links(PurePosixPath(page), read[page], tracked, read)
    assert not problems, f"{page}: broken links:\n" + "\n".join(problems)


def test_the_checker_finds_each_kind_of_broken_link() -> None:
    """The checker itself, on a page with one link of each kind, good and bad."""
    page = """# Title
## The model's signs, *in short*
[ok](docs/B.md) [ok](docs/B.md#the-model) ![ok](docs/img.png) [here](#title)
[ok](#the-models-signs-in-short) <img src="docs/img.png"> [ok](https://example.org/x.md)
[bad](../shared/B.md) ![bad](docs/results/gone.png) <img alt="x" src='docs/none.png'>
[bad anchor](docs/B.md#nowhere) [bad](#nowhere) [bad](/docs/B.md)
`[not a link](code.md)`

```
[not a link](fenced.md)
```
"""
    tracked = {"README.md", "docs/B.md", "docs/img.png"}
    read = {"README.md": page, "docs/B.md": "# B\n\n## The model\n"}
    problems = broken_links(PurePosixPath("README.md"), page, tracked, read)
    bad = [p.split(":")[0] for p in problems]
    assert bad == ["../shared/B.md", "docs/results/gone.png", "docs/B.md#nowhere", "#nowhere",
                   "/docs/B.md", "docs/none.png"]
