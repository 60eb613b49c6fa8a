"""The parsed-tree cache of parameter files: same tree from the cache, never a stale one."""

import subprocess
import sys

import pytest
import yaml

from amr_twin.model import parameter_tree
from amr_twin.model.config import ConfigError, load_config
from amr_twin.model.parameter_tree import DEFAULT_CONFIG, read_yaml


def _entries(folder):
    return (
        sorted(p.name for p in (folder / "yaml").glob("*.marshal"))
        if (folder / "yaml").exists()
        else []
    )


def test_cached_tree_equals_parsed_and_skips_pyyaml(tmp_path):
    env_dir = tmp_path / "cache"
    code = (
        "import sys; from amr_twin.model.parameter_tree import read_yaml, DEFAULT_CONFIG; "
        "import json; t = read_yaml(DEFAULT_CONFIG); print('yaml' in sys.modules); "
        "print(json.dumps(t, sort_keys=True))"
    )
    env = {**__import__("os").environ, "AMR_TWIN_CACHE_DIR": str(env_dir)}
    first = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    )
    second = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    )
    assert first.stdout.splitlines()[0] == "True"  # parsed: PyYAML imported
    assert second.stdout.splitlines()[0] == "False"  # from the cache: PyYAML not even imported
    assert first.stdout.splitlines()[1] == second.stdout.splitlines()[1]
    import json

    assert json.loads(second.stdout.splitlines()[1]) == yaml.safe_load(DEFAULT_CONFIG.read_text())
    assert len(_entries(env_dir)) == 1


def test_changed_file_is_parsed_again(tmp_path, monkeypatch):
    monkeypatch.setenv("AMR_TWIN_CACHE_DIR", str(tmp_path / "cache"))
    path = tmp_path / "p.yaml"
    path.write_text("sim:\n  timestep_s: {value: 0.001, unit: s, source: a}\n")
    assert read_yaml(path)["sim"]["timestep_s"]["value"] == 0.001
    path.write_text("sim:\n  timestep_s: {value: 0.002, unit: s, source: a}\n")
    assert read_yaml(path)["sim"]["timestep_s"]["value"] == 0.002  # a new key, not the old entry
    assert len(_entries(tmp_path / "cache")) == 2


def test_corrupt_entry_is_ignored_and_errors_still_name_the_file(tmp_path, monkeypatch):
    monkeypatch.setenv("AMR_TWIN_CACHE_DIR", str(tmp_path / "cache"))
    read_yaml(DEFAULT_CONFIG)
    (entry,) = (tmp_path / "cache" / "yaml").glob("*.marshal")
    entry.write_bytes(b"\x00garbage")
    assert read_yaml(DEFAULT_CONFIG) == yaml.safe_load(DEFAULT_CONFIG.read_text())
    bad = tmp_path / "bad.yaml"
    bad.write_text("sim: [unclosed\n")
    with pytest.raises(ConfigError, match="bad.yaml: not valid YAML"):
        read_yaml(bad)
    with pytest.raises(ConfigError, match="no such parameter file"):
        read_yaml(tmp_path / "missing.yaml")
    assert not any(
        p.name.startswith(".") for p in (tmp_path / "cache" / "yaml").iterdir()
    )  # no temporaries left


def test_unwritable_or_disabled_cache_still_loads(tmp_path, monkeypatch):
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("")
    monkeypatch.setattr(parameter_tree, "_trees", {})
    monkeypatch.setenv("AMR_TWIN_CACHE_DIR", str(blocker))
    assert load_config().wheel.radius_m > 0
    monkeypatch.setenv("AMR_TWIN_CACHE_DIR", "")
    assert parameter_tree.cache_dir("yaml") is None
    assert read_yaml(DEFAULT_CONFIG)["wheel"]["radius_m"]["value"] == load_config().wheel.radius_m
