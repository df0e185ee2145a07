"""An artifact is rebuilt exactly when the code that made it changes (husky_course.data.code).

Every key holds :func:`~husky_course.data.code.code_fingerprint` of the modules that build its
artifact; here the fingerprints are taken over edited copies of the package (``root=``), and the
real key functions are pointed at them, so nothing is trained.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from husky_course import cli
from husky_course.config import get_profile, with_world
from husky_course.course import diagnosis
from husky_course.data import code, store
from husky_course.evaluation import certificate, stale
from husky_course.training import builders, discs, memory

ROOT = Path(__file__).resolve().parents[1]
QUICK = get_profile("quick")
#: every module whose code enters a key, through a name it imports ``code_fingerprint`` by
USERS = (store, builders, memory, discs, certificate, diagnosis)
LABELS = Path("data/labels.py")
LABEL_LINE = "return survival(expand(world, sim.library, np.asarray(pose, float), horizon, cap=0.0, t0=t))"


def _copy(tmp_path: Path, name: str, edits: dict[Path, tuple[str, str]] | None = None) -> Path:
    """A copy of the package under ``tmp_path/name``, each ``edits[file] = (old, new)`` applied to the
    first ``old``."""
    root = tmp_path / name / "husky_course"
    shutil.copytree(code.package_root(), root, ignore=shutil.ignore_patterns("__pycache__"))
    for rel, (old, new) in (edits or {}).items():
        text = (root / rel).read_text()
        assert old in text, f"{rel} no longer holds {old!r}: update this test"
        (root / rel).write_text(text.replace(old, new, 1))
    return root


def _keys(monkeypatch: pytest.MonkeyPatch, root: Path) -> dict[str, object]:
    """Every key the store knows, with the code fingerprints taken over the package at ``root``."""
    def fingerprint(*modules: str, root_: Path | None = None) -> str:
        return code.code_fingerprint(*modules, root=root)

    for module in USERS:
        monkeypatch.setattr(module, "code_fingerprint", fingerprint)
    monkeypatch.setattr(builders, "module_fingerprint", lambda name: code.module_fingerprint(name, root))
    keys: dict[str, object] = {
        name: builders._parts(name, QUICK, "some-dataset")[2] for name in builders.MODELS
    }
    keys["labels"] = builders.labels_key(QUICK, "some-dataset")
    keys["dataset"] = store.dataset_dir(QUICK).name
    for kind in ("static", "moving"):
        keys[f"memory {kind}"] = memory.memory_fingerprint(with_world(QUICK, kind))
        keys[f"certificate {kind}"] = certificate.certificate_fingerprint(with_world(QUICK, kind))
    keys["discs"] = discs.disc_fingerprint(QUICK)
    keys["diagnosis"] = diagnosis.diagnosis_fingerprint(QUICK, "some-encoder", "some-dataset")
    return keys


def _docstring_and_comment_edits() -> dict[Path, tuple[str, str]]:
    return {
        LABELS: ('"""Ground truth about dataset images', '"""Ground truth (edited) about dataset images'),
        Path("sim/lattice.py"): ("\n\n\ndef ", "\n\n\n# a new comment\ndef "),
        Path("training/trainer.py"): ('"""One small trainer', '"""One small, well-documented trainer'),
        Path("planners/memory.py"): ('"""The memory student:', '"""The memory student (edited):'),
        Path("imitation/dagger.py"): ("\n\n\ndef ", "\n\n\n# a new comment\n\n\ndef "),
    }


def test_a_docstring_or_comment_edit_changes_no_fingerprint(tmp_path):
    a = _copy(tmp_path, "a")
    b = _copy(tmp_path, "b", _docstring_and_comment_edits())
    modules = ("husky_course.data.labels", "husky_course.training.builders", "husky_course.imitation.dagger",
               "husky_course.evaluation.certificate", "husky_course.data.collect")
    assert code.code_fingerprint(*modules, root=a) == code.code_fingerprint(*modules) != ""
    assert code.code_fingerprint(*modules, root=b) == code.code_fingerprint(*modules, root=a)
    assert code.library_fingerprint(b) == code.library_fingerprint(a) == code.library_fingerprint()


def test_a_docstring_edit_rebuilds_nothing(tmp_path, monkeypatch):
    before = _keys(monkeypatch, _copy(tmp_path, "a"))
    after = _keys(monkeypatch, _copy(tmp_path, "b", _docstring_and_comment_edits()))
    assert after == before


def test_a_label_function_change_rebuilds_the_labels_and_what_was_trained_on_them(tmp_path, monkeypatch):
    before = _keys(monkeypatch, _copy(tmp_path, "a"))
    edit = {LABELS: (LABEL_LINE, LABEL_LINE.replace("cap=0.0", "cap=0.1"))}
    after = _keys(monkeypatch, _copy(tmp_path, "b", edit))
    changed = {name for name in before if before[name] != after[name]}
    # the labels, the network distilled from them, the memory student (DAgger's labels) with its
    # certificate, and chapter 4's diagnosis (its reward labels come from the same module); the
    # dataset and the models trained on the dataset alone are kept
    assert changed == {"labels", "distilled", "memory static", "memory moving",
                       "certificate static", "certificate moving", "diagnosis"}


def test_a_model_change_rebuilds_that_model_and_what_builds_on_it(tmp_path, monkeypatch):
    before = _keys(monkeypatch, _copy(tmp_path, "a"))
    after = _keys(monkeypatch, _copy(tmp_path, "b", {Path("models/paper.py"): ("nn.ELU()", "nn.ReLU()")}))
    changed = {name for name in before if before[name] != after[name]}
    assert {"encoder_decoder", "reward_net", "diagnosis"} <= changed
    assert not changed & {"dataset", "labels", "discs"}


def test_closure_follows_relative_and_absolute_imports():
    found = code.closure("husky_course.training.builders")
    assert {"husky_course.data.labels", "husky_course.models.paper", "husky_course.sim.lattice"} <= set(found)
    assert not set(found) & code.NEUTRAL  # config and progress reach keys through values, or not at all
    assert "husky_course.planners.base" not in found  # a higher stage: never imported by training
    with pytest.raises(ValueError, match="no module"):
        code.code_fingerprint("husky_course.no_such_module")


def test_the_piece_networks_never_read_how_tracks_follow_pieces():
    """The disc and cut networks read the scan's pieces (planners/pieces.py), never the tracks of the
    moving course (planners/motion.py): an edit of tracking retrains neither, where the memory students,
    which read the tracks' velocities, do retrain."""
    from husky_course.training import cuts

    for made_by in (discs.DISCS_CODE, cuts.CUTS_CODE):
        found = set(code.closure(*made_by))
        assert "husky_course.planners.pieces" in found
        assert not found & {"husky_course.planners.motion", "husky_course.planners.walls",
                            "husky_course.planners.arrivals"}
    assert "husky_course.planners.motion" in code.closure(*memory.MEMORY_CODE)


def _make(tmp_path: Path, fingerprint: str, profile: str = "quick") -> str:
    if shutil.which("make") is None:
        pytest.skip("make is not installed")
    done = subprocess.run(
        ["make", "--no-print-directory", "-f", str(ROOT / "Makefile"), "-C", str(tmp_path), "book-cache",
         f"PROFILE={profile}", f"LIBRARY_FINGERPRINT=echo {fingerprint}"],
        capture_output=True, text=True, check=True,
    )
    return done.stdout


def _plant_book(tmp_path: Path) -> Path:
    cache = tmp_path / "_build" / ".jupyter_cache"
    (cache / "executed").mkdir(parents=True, exist_ok=True)
    (tmp_path / "_build" / "html").mkdir(exist_ok=True)
    return cache


def test_make_book_drops_the_execution_cache_when_the_library_changes(tmp_path):
    cache = _plant_book(tmp_path)
    assert "library's code changed" in _make(tmp_path, "aaa")  # a cache of unknown code: dropped
    assert not cache.exists() and not (tmp_path / "_build" / "html").exists()
    assert (tmp_path / "_build" / ".library").read_text().strip() == "aaa"
    _plant_book(tmp_path)
    assert _make(tmp_path, "aaa") == "" and cache.is_dir()  # the same library: kept
    assert "library's code changed" in _make(tmp_path, "bbb") and not cache.exists()
    _plant_book(tmp_path)
    assert "profile changed to full" in _make(tmp_path, "bbb", "full") and not cache.exists()
    assert (tmp_path / "_build" / ".profile").read_text().strip() == "full"


def test_the_book_asks_the_cli_for_the_library_fingerprint(capsys):
    recipe = subprocess.run(["make", "-n", "-f", str(ROOT / "Makefile"), "book-cache"], cwd=ROOT,
                            capture_output=True, text=True, check=True).stdout
    assert "-m husky_course fingerprint" in recipe
    assert "book-cache" in (ROOT / "Makefile").read_text().split("\nbook:")[1].split("\n\n")[0]
    assert cli.main(["fingerprint"]) == 0
    assert capsys.readouterr().out.strip() == code.library_fingerprint()


def test_clean_lists_a_stale_artifact_and_keeps_current_ones(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv(store.ARTIFACTS_ENV, str(tmp_path))
    moving = with_world(QUICK, "moving")
    current = [discs.disc_dir(QUICK), memory.memory_dir(moving), store.dataset_dir(QUICK)]
    models = tmp_path / "quick" / "models"
    planted = [models / "discs-0123456789ab", tmp_path / "quick" / "dataset-0123456789ab",
               tmp_path / "quick" / "evaluations" / "heuristic-0123456789ab.npz"]
    unchecked = models / "diagnosis-0123456789ab"
    for path in [*current, *planted[:2], unchecked]:
        path.mkdir(parents=True)
        (path / "model.pt").write_bytes(b"")
    planted[2].parent.mkdir()
    planted[2].write_bytes(b"not an evaluation")
    assert cli.main(["clean", "--profile", "quick", "--dry-run"]) == 0
    out = capsys.readouterr().out
    listed = {line.split(" ", 1)[1] for line in out.splitlines() if line.startswith("stale ")}
    assert listed == set(map(str, planted))
    assert f"kept (not checked) {unchecked}" in out
    assert all(p.exists() for p in [*planted, *current, unchecked]), "--dry-run deleted something"
    assert cli.main(["clean", "--profile", "quick"]) == 0
    assert not any(p.exists() for p in planted) and all(p.exists() for p in [*current, unchecked])


def test_clean_keeps_a_certificate_at_the_scale_its_key_records(tmp_path, monkeypatch):
    from dataclasses import replace

    monkeypatch.setenv(store.ARTIFACTS_ENV, str(tmp_path))
    bigger = replace(QUICK, guarantee=replace(QUICK.guarantee, worlds=QUICK.guarantee.worlds + 1))
    run = certificate.certificate_dir(bigger)
    run.mkdir(parents=True)
    assert run in {*stale.sweep(QUICK).stale}  # no key.json: nothing says which scale it is
    (run / certificate.KEY_FILE).write_text(json.dumps(certificate.certificate_fingerprint(bigger)))
    assert run in stale.sweep(QUICK).current


def test_clean_sorts_the_training_logs_as_the_artifacts_they_log(tmp_path, monkeypatch):
    """A TensorBoard log named as a current artifact is kept; one named as no current artifact is stale;
    a DAgger round's log, whose name this cannot judge, is kept unchecked."""
    monkeypatch.setenv(store.ARTIFACTS_ENV, str(tmp_path / "store"))
    fp = {"any": "key"}
    logs = tmp_path / "runs" / "quick"
    kept = logs / discs.disc_dir(QUICK).name
    old = store.runs_dir("discs", fp, QUICK)
    round_log = store.runs_dir("memory-round1", fp, QUICK)
    assert old.parent == logs
    for path in (kept, old, round_log):
        path.mkdir(parents=True)
    found = stale.sweep(QUICK)
    assert kept in found.current and old in found.stale and round_log in found.unchecked
    assert cli.main(["clean", "--profile", "quick"]) == 0
    assert kept.exists() and not old.exists() and round_log.exists()


def test_clean_keeps_the_realistic_disc_network_and_its_cut_network(tmp_path, monkeypatch):
    """Chapter 11 trains the disc network (and its cut network) on realistic senses: their artifacts are
    current, as the ideal ones are; a disc network of no current key is stale."""
    from husky_course.config import with_sensing
    from husky_course.training.cuts import cut_dir

    monkeypatch.setenv(store.ARTIFACTS_ENV, str(tmp_path / "store"))
    real = with_sensing(QUICK, "realistic")
    kept = [discs.disc_dir(real), cut_dir(real), discs.disc_dir(QUICK), cut_dir(QUICK)]
    old = store.model_dir("discs", {"any": "key"}, QUICK)
    assert len({p.name for p in kept}) == 4
    for path in (*kept, old):
        path.mkdir(parents=True)
    found = stale.sweep(QUICK)
    assert set(kept) <= set(found.current) and old in found.stale
