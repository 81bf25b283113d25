"""The documentation cannot rot: the site builds strictly and offline, the command-line page is the parser's, every
path, module, option and picture the README and the pages name exists, and the built pages show what they should
in headless chromium with the network off (screenshots read as pixels). The commands the pages show are run by
tests/test_docs_commands.py.
"""

from __future__ import annotations

import fcntl
import importlib
import os
import re
import subprocess
import sys
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from tests.support.browser_support import chromium, offline_prefix
from tests.support.docs_support import REPO, doc_pages, page_name, shell_blocks

INCLUDED = (REPO / "ur3hanoi" / "station" / "shipped" / "README.md", REPO / "bench" / "REPORT.md")
"""Files the site includes (pymdownx.snippets): named things in them are checked like the pages'."""

# ------------------------------------------------------------------------------------------------ the build


def _build(site: Path) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file",
                           str(REPO / "mkdocs.yml"), "--site-dir", str(site)], cwd=REPO, env=env,
                          capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="session")
def built_site(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, subprocess.CompletedProcess[str]]:
    """The site, built once per test run into a temporary folder (shared by the xdist workers under a lock)."""
    base = tmp_path_factory.getbasetemp()
    shared = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base  # the run's folder, not older runs'
    site, done = shared / "docs-site", shared / "docs-site.log"
    with open(shared / "docs-site.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not done.exists():
            proc = _build(site)
            done.write_text(f"{proc.returncode}\n{proc.stderr}")
        code, log = done.read_text().split("\n", 1)
    return site, subprocess.CompletedProcess([], int(code), "", log)


def test_the_site_builds_in_strict_mode_without_a_warning(built_site) -> None:  # type: ignore[no-untyped-def]
    site, proc = built_site
    assert proc.returncode == 0, proc.stderr[-4000:]
    assert not re.search(r"^(WARNING|ERROR)", proc.stderr, re.M), proc.stderr[-4000:]
    for page in ("index", "install", "tables", "calibration-file", "teach", "calibrate", "audit", "solve", "video",
                 "ros1", "ros2", "suction", "frames", "troubleshooting", "cli", "api", "benchmarks", "design",
                 "notebooks/01_kinematics", "notebooks/04_simulation"):
        assert (site / f"{page}.html").is_file(), page
    assert (site / "search" / "search_index.js").is_file()  # the offline plugin's search, from file://


def test_a_broken_link_or_anchor_fails_the_strict_build(tmp_path: Path) -> None:
    """The site's strictness (its validation settings and --strict) does fail a build: a two-page site with the
    same settings, without the slow plugins, whose home page links to a missing page and a missing anchor."""
    import yaml

    config = yaml.safe_load((REPO / "mkdocs.yml").read_text())
    config.update(docs_dir=str(tmp_path / "docs"), site_dir=str(tmp_path / "site"), nav=["index.md", "other.md"],
                  plugins=["search", "offline"], hooks=[], extra={})
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "other.md").write_text("# Other\n\n## A heading\n")
    (tmp_path / "mkdocs.yml").write_text(yaml.safe_dump(config))
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    for link, words in (("[ok](other.md#a-heading)", None), ("[missing](no-such-page.md)", "no-such-page.md"),
                        ("[anchor](other.md#no-such-anchor)", "no-such-anchor")):
        (tmp_path / "docs" / "index.md").write_text(f"# Home\n\nSee {link}.\n")
        proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(tmp_path / "mkdocs.yml")],
                              env=env, capture_output=True, text=True, timeout=300)
        if words is None:
            assert proc.returncode == 0, proc.stderr[-2000:]
        else:
            assert proc.returncode != 0 and words in proc.stderr, proc.stderr[-2000:]


def test_the_built_pages_fetch_nothing_from_the_network(built_site) -> None:  # type: ignore[no-untyped-def]
    site, _ = built_site
    remote = re.compile(r"<script[^>]+src=\"(?:https?:)?//|<link[^>]+href=\"(?:https?:)?//[^\"]*\"[^>]*stylesheet|"
                        r"rel=\"stylesheet\"[^>]+href=\"(?:https?:)?//|import\(\s*[\"']https?://|"
                        r"@import\s+url\(\s*[\"']?https?://|fonts\.googleapis|fonts\.gstatic", re.I)
    offenders = {}
    for page in site.rglob("*.html"):
        found = remote.findall(page.read_text(encoding="utf-8"))
        if found:
            offenders[str(page.relative_to(site))] = found[:3]
    assert not offenders, offenders


# ------------------------------------------------------------------------------------------------ the CLI page


def test_the_cli_page_is_the_parsers_help() -> None:
    sys.path.insert(0, str(REPO / "tools"))
    try:
        from update_cli_page import PAGE, render
    finally:
        sys.path.pop(0)
    page = PAGE.read_text()
    assert render(page) == page, "docs/cli.md is stale: run `make docs`"


def test_the_example_table_is_what_the_pictures_script_makes(tmp_path: Path) -> None:
    """docs/examples/hand_recorded.yaml (the audit page's table and picture) comes from tools/make_pictures.py."""
    sys.path.insert(0, str(REPO / "tools"))
    try:
        from make_pictures import EXAMPLE, hand_recorded_table
    finally:
        sys.path.pop(0)
    assert hand_recorded_table(tmp_path) == EXAMPLE.read_text(), "stale: run `make pictures`"


# ------------------------------------------------------------------------------------------------ named things

TOPICS = {"ur3hanoi/spawn", "ur3hanoi/remove_block"}
"""ROS topic names the pages mention, which look like paths."""

OTHER_PROGRAMS_OPTIONS = {"--simulator": "the course's lab2_exec.py",
                          "--ain0-below": "tests/support/lab2_exec_starter.py"}
"""Options the pages mention that belong to another program than ur3hanoi."""

_PATH = re.compile(r"(?<![\w./$~-])((?:ur3hanoi|tests|tools|bench|docs|notebooks|tables)/[\w./*<>-]*[\w*/])")
_DOTTED = re.compile(r"(?<![\w./-])(ur3hanoi(?:\.[A-Za-z_]\w*)+)")
_OPTION = re.compile(r"(?<![\w-])(--[a-z][\w-]*)")
_SPAN = re.compile(r"`([^`\n]+)`")
_IMAGE = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")


@cache
def _parser_options() -> dict[str, frozenset[str]]:
    """Every command's long options, and "" for the union of all of them and the top level's."""
    import argparse

    from ur3hanoi.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    top = {s for a in parser._actions for s in a.option_strings}
    options = {name: frozenset(s for a in p._actions for s in a.option_strings if s.startswith("--")) | top
               for name, p in sub.choices.items()}
    options[""] = frozenset().union(*options.values())
    return options


def _texts() -> list[tuple[str, str]]:
    return [(page_name(p), p.read_text(encoding="utf-8")) for p in (*doc_pages(), *INCLUDED)]


def _command_of(span: str) -> str:
    """The ur3hanoi command a code span or command line names (``ur3hanoi solve ...`` or ``solve ...``), or ""."""
    words = span.split()
    if words and words[0] == "ur3hanoi":
        words = words[1:]
    return words[0] if words and words[0] in _parser_options() else ""


def _missing_path(name: str) -> bool:
    name = name.rstrip("/.")
    if name in TOPICS:
        return False
    if "<" in name or re.search(r"(?<![A-Za-z])[A-Z]{3,}(?![A-Za-z])", name):  # a template: notebooks/NAME.ipynb
        name = re.split(r"[^/]*(?:<|(?<![A-Za-z])[A-Z]{3,}(?![A-Za-z]))", name, maxsplit=1)[0] or "."
    return not any(REPO.glob(name)) if "*" in name else not (REPO / name).exists()


def _missing_object(dotted: str) -> bool:
    parts = dotted.split(".")
    for n in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:n]))
        except ImportError:
            continue
        try:
            for attr in parts[n:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return True
        return False
    return True


def named_problems(name: str, text: str) -> list[str]:
    """What the text ``name`` names that does not exist: paths, modules and objects, options, pictures."""
    problems = [f"{name}: path {p} does not exist" for p in _PATH.findall(text) if _missing_path(p)]
    problems += [f"{name}: {d} is no module or object" for d in set(_DOTTED.findall(text)) if _missing_object(d)]
    options = _parser_options()
    # Options: in a code span or a command line naming a command, that command's; anywhere else, any command's.
    units = _SPAN.findall(text) + [ln for ln in text.splitlines() if ln.lstrip().startswith("ur3hanoi ")]
    for unit in units:
        command = _command_of(unit)
        for opt in _OPTION.findall(unit):
            if opt.split("=")[0] not in options[command] and opt not in OTHER_PROGRAMS_OPTIONS:
                problems.append(f"{name}: {opt} is no option of ur3hanoi {command or '(any command)'}: {unit!r}")
    for opt in set(_OPTION.findall(text)):
        if opt not in options[""] and opt not in OTHER_PROGRAMS_OPTIONS:
            problems.append(f"{name}: {opt} is no option of any ur3hanoi command")
    base = REPO if name == "README.md" else (REPO / name).parent
    problems += [f"{name}: picture {src} does not exist" for src in _IMAGE.findall(text)
                 if not src.startswith(("http:", "https:")) and not (base / src).is_file()]
    return sorted(set(problems))


def test_everything_the_pages_name_exists() -> None:
    problems = [p for name, text in _texts() for p in named_problems(name, text)]
    assert not problems, "\n".join(problems)


def test_a_page_naming_what_does_not_exist_is_caught() -> None:
    text = ("See `ur3hanoi/no_such.py`, `tools/no_such/NAME.py` and "
            "`ur3hanoi.station.calibration.NoSuchThing`; run `ur3hanoi plan --no-such-option`, "
            "or `solve --fit` (an option of check-table only), then --also-missing.\n![a picture](no_such.png)\n"
            "ur3hanoi tables lab_sim --key sim_pos --nope -o x.yaml\n")
    problems = "\n".join(named_problems("docs/page.md", text))
    for words in ("path ur3hanoi/no_such.py does not exist", "path tools/no_such/NAME.py does not exist",
                  "ur3hanoi.station.calibration.NoSuchThing is no module",
                  "--no-such-option is no option of ur3hanoi plan", "--fit is no option of ur3hanoi solve",
                  "--also-missing is no option of any ur3hanoi command", "picture no_such.png does not exist",
                  "--nope is no option of ur3hanoi tables"):
        assert words in problems, problems
    assert named_problems("docs/page.md", "`check-table --fit`, `ur3hanoi/station/shipped/lab_sim.yaml`, "
                                          "`tests/NAME.py`, `ur3hanoi.robot.model.JointLimits`, "
                                          "![the audit](audit.png)") == []


def test_the_readme_stays_a_front_door() -> None:
    readme = (REPO / "README.md").read_text()
    assert len(readme.splitlines()) <= 200
    assert "make solve" in readme and "make test" in readme and "![" in readme
    blocks = shell_blocks(REPO / "README.md")
    assert blocks and not any(b.run for b in blocks), "the README shows commands; their pages run them"


# ------------------------------------------------------------------------------------------------ in a browser

HEADER_RGB = (63, 81, 181)
"""Material's indigo, the header band of every page (theme.palette.primary)."""
PLOT_BLUE, PLOT_RED = (31, 119, 180), (214, 39, 40)
"""matplotlib's default blue and red: the audit picture's accepted entries and flagged entry."""


def _browse(url: str, tmp: Path, name: str, size: tuple[int, int]) -> np.ndarray:
    """A screenshot of ``url`` in Debian's headless chromium, network off, fresh profile, as RGB pixels."""
    out = tmp / f"{name}.png"
    args = [*offline_prefix(), chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
            "--disable-background-networking", "--disable-component-update", "--disable-sync", "--hide-scrollbars",
            f"--user-data-dir={tmp / ('profile-' + name)}", f"--window-size={size[0]},{size[1]}",
            f"--screenshot={out}", url]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=180)
    assert proc.returncode == 0 and out.is_file(), proc.stderr[-2000:]
    return np.asarray(Image.open(out).convert("RGB")).astype(int)


def _near(img: np.ndarray, rgb: tuple[int, int, int], tol: int = 12) -> np.ndarray:
    return np.all(np.abs(img - np.array(rgb)) <= tol, axis=-1)


def test_the_home_page_shows_the_header_the_text_and_the_replay_picture(built_site, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    site, _ = built_site
    img = _browse((site / "index.html").as_uri(), tmp_path, "home", (1280, 900))
    header = _near(img[:40], HEADER_RGB)
    assert header.mean() > 0.7, f"the header band is {header.mean():.0%} indigo"
    body = img[60:]
    assert (body.max(axis=-1) < 100).sum() > 2000, "no dark text on the page"
    # The replay picture: its sky-blue background and the brown table (only the picture has them).
    sky = (body[..., 2] > 200) & (body[..., 0] < 170) & (body[..., 2] - body[..., 0] > 60)
    table = (np.abs(body - np.array((140, 100, 70))) < 40).all(axis=-1)
    assert sky.sum() > 20000 and table.sum() > 5000, f"the replay picture is not drawn: {sky.sum()} sky, " \
                                                     f"{table.sum()} table px"


def test_the_audit_page_shows_the_audit_picture(built_site, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    site, _ = built_site
    img = _browse((site / "audit.html").as_uri(), tmp_path, "audit", (1280, 2200))
    assert _near(img[:40], HEADER_RGB).mean() > 0.7
    blue, red = _near(img, PLOT_BLUE, 20), _near(img, PLOT_RED, 20)
    assert blue.sum() > 150 and red.sum() > 40, f"the audit picture is not drawn: {blue.sum()} blue, {red.sum()} red px"
    rows = np.flatnonzero(blue.any(axis=1))
    assert rows.min() > 40, "plot colours in the header"
