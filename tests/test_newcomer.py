"""The paths a newcomer takes: installing, reading an error, running the command it names.

* ``make install`` fails loudly, with pip's own message, when any pip step fails, and installs
  torch's CPU build unless told otherwise (``TORCH_INDEX``); checked on a stand-in Python that
  records what it was asked and fails where told, so no package is installed here.
* The Python version the README and ``pyproject.toml`` state is the one the tests need.
* A missing artifact's message names a command that the CLI accepts and that builds *that*
  artifact (``--world moving`` included); the CLI's docstring shows every subcommand.
* Only ``HUSKY_STATIC_WIDGETS`` makes widgets static: ``CI`` changes nothing in the library.
* A profile *name* where a :class:`~husky_course.config.Profile` is expected is a clear
  :class:`~husky_course.config.ConfigError` (``make bench`` once died of an ``AttributeError``).
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from husky_course import cli, progress
from husky_course.config import ConfigError, get_profile, with_world
from husky_course.data.store import ARTIFACTS_ENV
from husky_course.planners.base import PlannerError
from husky_course.planners.registry import LEARNED_PLANNERS, make_planner
from husky_course.training import builders
from husky_course.training.trainer import CheckpointError
from husky_course.ui import widgets

ROOT = Path(__file__).resolve().parents[1]
QUICK = get_profile("quick")

# a stand-in for the venv's python: logs its arguments, fails (as pip does) where $FAIL_ON matches
FAKE_PYTHON = """#!/usr/bin/env bash
echo "$*" >> "$(dirname "$0")/../calls.log"
if [ -n "${FAIL_ON:-}" ] && [[ " $* " == *"$FAIL_ON"* ]]; then
  echo "ERROR: No matching distribution found for fakepkg==9.9 (stand-in pip, step '$FAIL_ON')" >&2
  exit 1
fi
"""


def fake_venv(tmp_path: Path) -> Path:
    venv = tmp_path / "venv"
    (venv / "bin").mkdir(parents=True)
    python = venv / "bin" / "python"
    python.write_text(FAKE_PYTHON)
    python.chmod(0o755)
    return venv


def make_install(venv: Path, *extra: str, fail_on: str = "") -> subprocess.CompletedProcess:
    if shutil.which("make") is None:
        pytest.fail("no `make` on this machine: the course's two commands are make targets")
    return subprocess.run(
        ["make", "--no-print-directory", "-C", str(ROOT), "install", f"VENV={venv}", *extra],
        capture_output=True, text=True, timeout=120, env={**_env(), "FAIL_ON": fail_on},
    )


def _env() -> dict[str, str]:
    return {k: v for k, v in os.environ.items() if k not in ("MAKEFLAGS", "MFLAGS", "MAKELEVEL")}


@pytest.mark.parametrize("step", ["--upgrade pip", "torch==", "-r requirements.txt", "-e ."])
def test_a_failed_pip_step_fails_make_install_with_pips_message(tmp_path: Path, step: str) -> None:
    venv = fake_venv(tmp_path)
    done = make_install(venv, fail_on=step)
    out = done.stdout + done.stderr
    assert done.returncode != 0, f"make install went on after pip failed at {step!r}:\n{out}"
    assert f"No matching distribution found for fakepkg==9.9 (stand-in pip, step '{step}')" in out, out
    assert not (venv / ".installed").exists()
    calls = (venv / "calls.log").read_text()
    assert step in calls.splitlines()[-1], f"make went past the failed step:\n{calls}"


def test_make_install_takes_torch_from_the_cpu_index_unless_told(tmp_path: Path) -> None:
    pinned = re.search(r"^torch==[\w.]+", (ROOT / "requirements.txt").read_text(), re.M)
    assert pinned, "requirements.txt pins no torch release"
    for extra, index in (((), "https://download.pytorch.org/whl/cpu"), (("TORCH_INDEX=",), None)):
        venv = fake_venv(tmp_path / str(len(extra)))
        done = make_install(venv, *extra, fail_on="-r requirements.txt")  # stop before the checks
        torch_step = [c for c in (venv / "calls.log").read_text().splitlines() if pinned.group(0) in c]
        assert len(torch_step) == 1, f"{done.stdout}{done.stderr}"
        args = shlex.split(torch_step[0])
        assert args[:4] == ["-m", "pip", "install", "--quiet"] and args[-1] == pinned.group(0)
        if index is None:  # TORCH_INDEX= : PyPI's build (CUDA on Linux), no extra index
            assert "--extra-index-url" not in args
        else:
            assert args[args.index("--extra-index-url") + 1] == index


def test_the_stated_python_is_the_one_the_tests_need() -> None:
    """``tests/test_layout.py`` imports ``tomllib`` (3.11): pyproject and README must say 3.11+."""
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["requires-python"] == ">=3.11"
    readme = (ROOT / "README.md").read_text()
    stated = set(re.findall(r"Python (3\.\d+)\+", readme))
    assert stated == {"3.11"}, f"README states Python {stated}"
    assert sys.version_info >= (3, 11)


def _message(fn: Callable[[], object]) -> str:
    with pytest.raises((CheckpointError, PlannerError)) as caught:
        fn()
    return str(caught.value)


def _missing_messages(profile) -> dict[str, str]:  # type: ignore[no-untyped-def]
    from husky_course.evaluation.certificate import load_certificate
    from husky_course.training.cuts import load_cuts
    from husky_course.training.discs import load_discs
    from husky_course.training.memory import load_memory

    found = {f"load {n}": _message(lambda n=n: builders.load(n, profile)) for n in builders.BUILDERS}
    for n in LEARNED_PLANNERS:
        found[f"planner {n}"] = _message(lambda n=n: make_planner(n, profile=profile))
    found["load_memory"] = _message(lambda: load_memory(profile))
    found["load_discs"] = _message(lambda: load_discs(profile))
    found["load_cuts"] = _message(lambda: load_cuts(profile))
    found["load_certificate"] = _message(lambda: load_certificate(profile))
    return found


@pytest.mark.parametrize("world", ["static", "moving"])
def test_a_missing_artifact_names_the_command_that_builds_it(
    world: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from husky_course.training.cuts import cut_dir
    from husky_course.training.discs import disc_dir

    monkeypatch.setenv(ARTIFACTS_ENV, str(tmp_path / "empty-store"))
    profile = with_world(QUICK, world)
    parser = cli.build_parser()
    for where, message in _missing_messages(profile).items():
        commands = re.findall(r"`python -m husky_course ([^`]+)`", message)
        assert len(commands) == 1, f"{where}: {message}"
        args = parser.parse_args(shlex.split(commands[0]))  # the CLI accepts it (else SystemExit)
        assert args.command == "train", f"{where}: {message}"
        built = with_world(get_profile(args.profile), args.world)
        if args.model == "discs":  # one network for both courses: the same artifact either way
            assert disc_dir(built) == disc_dir(profile), f"{where}: {message}"
        elif args.model == "cuts":  # so is the cut network that reads with it
            assert cut_dir(built) == cut_dir(profile), f"{where}: {message}"
        else:
            assert built == profile, f"{where}: `{commands[0]}` builds the {args.world} course's artifact"


def test_the_cli_docstring_shows_every_subcommand() -> None:
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    doc = cli.__doc__ or ""
    listed = re.match(r"Command line: ``python -m husky_course \{([a-z,]+)\} \.\.\.``\.", doc.splitlines()[0])
    assert listed and set(listed.group(1).split(",")) == set(sub.choices), doc.splitlines()[0]
    for name in sub.choices:
        assert f"``python -m husky_course {name} " in doc, f"no example of `{name}` in the CLI's docstring"


def test_only_husky_static_widgets_makes_widgets_static(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(progress.STATIC_ENV, raising=False)
    monkeypatch.setenv("CI", "true")  # CI runs what a student's kernel runs
    assert not progress.static_mode()
    monkeypatch.setattr(widgets, "static_mode", progress.static_mode)
    for value, static in (("1", True), ("true", True), ("0", False), ("", False)):
        monkeypatch.setenv(progress.STATIC_ENV, value)
        assert progress.static_mode() is static, value
        if static:
            assert not widgets.widgets_live()
    monkeypatch.setenv(progress.STATIC_ENV, "1")
    assert type(progress.tqdm(range(1), disable=True)).__module__ == "tqdm.std"


def test_a_profile_name_where_a_profile_is_expected_is_a_config_error() -> None:
    for name in ("joint", "distilled"):
        with pytest.raises(ConfigError, match="expected a Profile, got 'quick'"):
            builders.load(name, "quick")  # type: ignore[arg-type]
    with pytest.raises((ConfigError, PlannerError), match="expected a Profile"):
        make_planner("distilled", profile="quick")
