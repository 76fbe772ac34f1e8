"""Finding a libLLVM that Dr.Jit 1.5 accepts (>= 16), and saying what to install when there is none."""

from __future__ import annotations

import pytest

import mcrt.llvm as llvm


def test_version_from_file_names():
    assert llvm._major("/usr/lib/x86_64-linux-gnu/libLLVM-15.so.1") == 15
    assert llvm._major("/venv/lib/libLLVM.so.23.1") == 23
    assert llvm._major("/usr/lib/llvm-19/lib/libLLVM.so.19.1") == 19
    assert llvm._major("/venv/lib/libLLVM.so") is None


@pytest.fixture
def fake(monkeypatch, tmp_path):
    """Pretend the system and the environment hold the named libraries; restore mcrt's real choice after."""
    import os

    saved_env, saved_problem = os.environ.get("DRJIT_LIBLLVM_PATH"), llvm._problem

    def make(system, wheel):
        paths = {}
        for name in system + wheel:
            p = tmp_path / name
            p.write_bytes(b"")
            paths[name] = str(p)
        monkeypatch.setattr(llvm, "_system_candidates", lambda: [paths[n] for n in system])
        monkeypatch.setattr(llvm, "_wheel_candidates", lambda: [paths[n] for n in wheel])
        monkeypatch.delenv("DRJIT_LIBLLVM_PATH", raising=False)
        return paths

    yield make
    monkeypatch.undo()
    if saved_env is not None:
        os.environ["DRJIT_LIBLLVM_PATH"] = saved_env
    llvm._problem = saved_problem


def test_prefers_the_newest_acceptable_system_library(fake):
    paths = fake(["libLLVM-15.so.1", "libLLVM-19.so.1", "libLLVM-17.so.1"], ["libLLVM.so.23.1"])
    assert llvm.find_llvm() == paths["libLLVM-19.so.1"]
    llvm.require_llvm()


def test_falls_back_to_the_wheel_when_the_system_has_only_llvm15(fake):
    paths = fake(["libLLVM-15.so.1", "libLLVM-14.so.1"], ["libLLVM.so.23.1"])
    assert llvm.find_llvm() == paths["libLLVM.so.23.1"]


def test_none_found_says_what_to_install(fake):
    fake(["libLLVM-15.so.1"], [])
    assert llvm.find_llvm() is None
    with pytest.raises(RuntimeError, match=r"found only .*libLLVM-15\.so\.1.*pip install karellen-llvm-core.*apt-get install libllvm19"):
        llvm.require_llvm()


def test_user_setting_is_respected_and_checked(fake, monkeypatch, tmp_path):
    fake(["libLLVM-19.so.1"], [])
    mine = tmp_path / "custom" / "libLLVM.so"
    monkeypatch.setenv("DRJIT_LIBLLVM_PATH", str(mine))
    assert llvm.find_llvm() is None
    with pytest.raises(RuntimeError, match="does not exist"):
        llvm.require_llvm()
    mine.parent.mkdir()
    mine.write_bytes(b"")
    assert llvm.find_llvm() == str(mine)
