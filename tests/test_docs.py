"""The documentation's links resolve in every clone.

Every relative link and image of ``README.md`` and ``docs/*.md`` (Markdown ``[text](target)``
and ``![alt](target)``, HTML ``<img src>`` and ``<a href>``) must point to a file tracked by
git (``git ls-files``): a file that exists only on one machine, or that ``.gitignore`` hides,
is broken for everyone else. An anchor (``#heading``) into a Markdown file must name one of
its headings. Links with a scheme (``https:``, ``mailto:``) are not checked.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import tarfile
import unicodedata
from email.message import Message
from email.parser import Parser
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


# -- the long description a package index shows (setup.py) ------------------------------------

BUILD_SDIST = "from setuptools import build_meta as b; print(b.build_sdist({out!r}))"
WHEEL_METADATA = (
    "from setuptools import build_meta as b; print(b.prepare_metadata_for_build_wheel({out!r}))"
)


def _copy_tracked_tree(dest: Path) -> Path:
    """The repository's tracked files, copied to ``dest`` (builds run on the copy)."""
    for name in tracked_files():
        source = ROOT / name
        if source.is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, dest / name)
    return dest


def _run(code: str, cwd: Path) -> str:
    out = subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-3000:]
    return out.stdout.strip().splitlines()[-1]


def _build(tree: Path) -> tuple[Message, Message, set[str]]:
    """The sdist's PKG-INFO, the wheel's METADATA built from the unpacked sdist, and the
    sdist's files (paths inside the project folder)."""
    sdist = tree / "dist" / _run(BUILD_SDIST.format(out="dist"), tree)
    with tarfile.open(sdist) as tar:
        tar.extractall(tree / "unpacked", filter="data")
        names = {"/".join(n.split("/")[1:]) for n in tar.getnames()}
    project = next((tree / "unpacked").iterdir())
    pkg_info = Parser().parsestr((project / "PKG-INFO").read_text(encoding="utf-8"))
    (project / "meta").mkdir()
    dist_info = _run(WHEEL_METADATA.format(out=str(project / "meta")), project)
    metadata = Parser().parsestr((project / "meta" / dist_info / "METADATA").read_text(
        encoding="utf-8"))
    return pkg_info, metadata, names


def _relative(targets: list[str]) -> list[str]:
    return [t for t in targets if t and not _SCHEME.match(t) and not t.startswith("#")]


def test_long_description_has_no_relative_links_and_names_files_the_sdist_ships(tmp_path):
    """No base URL set (none exists yet): README's links become the names of files that
    the source distribution contains, and the wheel carries the same description."""
    pkg_info, metadata, names = _build(_copy_tracked_tree(tmp_path))
    description = pkg_info.get_payload()
    assert pkg_info["Description-Content-Type"] == "text/markdown"
    assert metadata.get_payload() == description
    readme_links = _relative(links((ROOT / "README.md").read_text()))
    assert readme_links, "README.md has no relative links: the rewrite is untested"
    assert _relative(links(description)) == []
    for target in readme_links:
        path = target.split("#")[0]
        assert f"`{path}`" in description, f"{path} is not named in the long description"
        assert path in names, f"{path} is named in the long description but not in the sdist"
    # Nothing else changed: the text outside the links is README's.
    assert description.startswith("# roller-gym\n")
    assert "## Set-up: two commands" in description


def test_long_description_links_are_absolute_under_the_configured_base_url(tmp_path):
    """With [tool.roller_gym.readme] base-url set, each relative link is that URL + its path
    (images under image-base-url), and code is left alone."""
    tree = _copy_tracked_tree(tmp_path)
    pyproject = tree / "pyproject.toml"
    base, raw = "https://example.org/org/roller-gym/blob/v0/", "https://example.org/raw/v0/"
    text = pyproject.read_text()
    assert 'base-url = ""' in text and 'image-base-url = ""' in text
    pyproject.write_text(text.replace('image-base-url = ""', f'image-base-url = "{raw}"')
                         .replace('\nbase-url = ""', f'\nbase-url = "{base}"'))
    readme = tree / "README.md"
    readme.write_text(readme.read_text() + "\n![a plot](docs/benchmarks/energy.png)\n"
                      "`[not a link](docs/PHYSICS.md)`\n")
    description = _build(tree)[0].get_payload()
    source = readme.read_text()
    expected = [(raw if f"]({t})" in source and re.search(rf"!\[[^\]]*\]\({re.escape(t)}\)",
                                                      source) else base) + t
                for t in _relative(links(source))]
    assert _relative(links(description)) == []
    assert [t for t in links(description) if t.startswith("https://example.org/")] == expected
    assert "`[not a link](docs/PHYSICS.md)`" in description


# -- what the README tells a newcomer to run -----------------------------------------------

#: A pip command that fetches roller-gym by name from a package index.
_FROM_INDEX = re.compile(r"""pip (?:install|download)[^`\n]*?(?<![\w./-])["']?roller-gym\b""")
CPU_INDEX = "--extra-index-url https://download.pytorch.org/whl/cpu"


def _readme_section(title: str) -> str:
    text = (ROOT / "README.md").read_text()
    start = text.index(f"\n## {title}\n")
    end = text.find("\n## ", start + 1)
    return text[start:end if end >= 0 else None]


def _long_description_note() -> str:
    import importlib.util

    spec = importlib.util.spec_from_file_location("roller_gym_setup", ROOT / "setup.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.NOTE


@pytest.mark.parametrize("source", ["README.md", "setup.py NOTE"])
def test_installing_by_name_is_offered_only_for_once_the_package_is_published(source):
    """roller-gym is not on PyPI: every pip command that fetches it by name sits in a
    paragraph that says it works once the package is published, and the README's first pip
    command installs from the clone."""
    text = (ROOT / "README.md").read_text() if source == "README.md" else _long_description_note()
    paragraphs = re.split(r"\n\s*\n", text)
    by_name = [p for p in paragraphs if _FROM_INDEX.search(p)]
    assert by_name, f"{source}: no pip command by name found (the check is vacuous)"
    for paragraph in by_name:
        assert "once roller-gym is published" in " ".join(paragraph.split()).lower(), paragraph
    if source == "README.md":
        first = re.search(r"pip install[^\n`#]*", text).group(0).strip()
        assert first == "pip install .", first


def test_the_checker_of_install_lines_tells_a_name_from_a_path():
    assert _FROM_INDEX.search('pip install "roller-gym[zoo]"')
    assert _FROM_INDEX.search("pip download --no-deps --no-binary :all: roller-gym")
    assert not _FROM_INDEX.search('pip install ".[zoo]"')
    assert not _FROM_INDEX.search("pip install /work/roller-gym")


def test_every_install_command_that_brings_torch_names_the_cpu_index():
    """Each command of the install section's code that installs an extra with torch (as
    pyproject.toml's extras say) carries the index of torch's CPU build."""
    from base_install import pyproject_extra

    code = "\n".join(re.findall(r"^```bash\n(.*?)^```", _readme_section("Install"),
                                re.M | re.S))
    commands = re.findall(r"""pip install [^#\n]*""", code)
    with_torch = [c for c in commands
                  if (m := re.search(r"""\.\[([\w,]+)\]""", c)) and "torch" in pyproject_extra(
                      m.group(1))]
    assert with_torch, "no install command with torch in the install section"
    for command in with_torch:
        assert CPU_INDEX in command, command


def test_readme_client_table_is_roller_gym_clients():
    """The README's table of clients and their autoreset modes is roller_gym.clients.CLIENTS."""
    from roller_gym.clients import CLIENTS

    rows = re.findall(r"^\| (\w+) \| `\"(\w+)\"`[^|]* \| ([^|]+) \|$",
                      _readme_section("Other clients"), re.M)
    assert [(name, mode) for name, mode, _ in rows] == [
        (c.name, c.autoreset_mode.name.lower()) for c in CLIENTS.values()]


def test_the_readmes_table_of_keyword_arguments_is_the_settings_record():
    """The README's table of the environments' keywords is the text of
    roller_gym.config.Settings (names, meanings and defaults declared once)."""
    from roller_gym.config import settings_table

    assert settings_table() in (ROOT / "README.md").read_text()
