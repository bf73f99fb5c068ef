"""`wendel bench overhead` with WENDEL_BENCH_BASE: which scene file each tree runs (issue 20)."""

from __future__ import annotations

from wendel.bench.overhead import scene_for


def test_the_base_runs_its_own_scene_file_only_when_asked(tmp_path, monkeypatch):
    this = tmp_path / "this" / "workflows" / "a.toml"
    base = tmp_path / "base"
    (base / "workflows").mkdir(parents=True)
    (base / "workflows" / "a.toml").write_text("")
    monkeypatch.delenv("WENDEL_BENCH_OWN_SCENES", raising=False)
    assert scene_for(base, this) == this and scene_for(None, this) == this
    monkeypatch.setenv("WENDEL_BENCH_OWN_SCENES", "1")
    assert scene_for(base, this) == base / "workflows" / "a.toml" and scene_for(None, this) == this
    assert scene_for(base, this.with_name("b.toml")) == this.with_name("b.toml")      # the base has none: this one's
