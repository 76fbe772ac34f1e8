"""The Gradescope image built for real: setup.sh in a clean Debian root, then hand-ins graded under 768 MiB.

A minimal Debian 12 root (``mmdebstrap --variant=minbase bookworm``; Gradescope's
Ubuntu images cannot be reached from CI, Debian's archive can) is built once into
a cache folder (``$MCRT_CACHE/clean_root`` or ``~/.cache/mcrt/clean_root``) as a
tarball and unpacked afresh for every run. ``mcrt gradescope-zip --mode code``
builds the zip; its files go to the root's /autograder/source and setup.sh runs
there as Gradescope runs it, as root, with apt-get and pip from the network
(nothing of this machine's Python or packages is visible in the root). Then
run_autograder grades, in the same image, each under Gradescope's default limits,
768 MiB of memory over all its processes and half a CPU (cgroup v2 memory.max and
cpu.max, else v1 memory.limit_in_bytes and cpu.cfs_quota_us):

* a code-mode hand-in whose functions are correct but whose
  ``sample_cosine_hemisphere`` reports who runs it (uid, euid) and whether
  /etc/shadow is readable, by raising: the test checks the student code ran as
  a non-root uid that could not read /etc/shadow, and that the other checks
  passed;
* in image mode (the mode file switched): a correct render (full marks), a
  biased render (fewer points, the bug named) and an empty hand-in (score 0
  with a reason).

The root is entered with bubblewrap (``--bind ROOT /``, so it is the root of a
mount namespace, where the sandbox's own bubblewrap can run), with /proc, /dev,
/sys and resolv.conf, and pip given the host's CA bundle (PIP_CERT).

It downloads about 300 MB and takes minutes, so it runs only when asked
(``long``: ``MCRT_SLOW=1``, which ``.ci/run`` sets; tests/conftest.py). Under CI,
a missing mmdebstrap, bwrap or cgroup fails rather than skips. It prints the
image's size and the phases' times.
"""

from __future__ import annotations

import base64
import os
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import pytest

from test_gradescope import ASSIGNMENT, _render, check_results
from test_grade import GOOD

pytestmark = [pytest.mark.slow, pytest.mark.long]  # a Debian root built, about 300 MB downloaded

ROOT = Path(__file__).resolve().parent.parent
SUITE = "bookworm"
MEMORY = 768 * 2**20
CA = Path("/etc/ssl/certs/ca-certificates.crt")
PATH = "/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin"
# The probe: the student's code says who runs it, in the check's failure message (results.json shows it).
PROBE = '''def sample_cosine_hemisphere(u1, u2):
    import os
    try:
        open("/etc/shadow", "rb").read(1)
        shadow = "readable"
    except OSError as e:
        shadow = f"unreadable ({type(e).__name__})"
    raise RuntimeError(f"PROBE uid={os.getuid()} euid={os.geteuid()} shadow={shadow}")

def _unused_sample(u1, u2):'''


def _need(what: str, ok: bool) -> None:
    if not ok:
        (pytest.fail if os.environ.get("CI") else pytest.skip)(f"needs {what}")


def _cache_dir() -> Path:
    base = Path(os.environ["MCRT_CACHE"]) if os.environ.get("MCRT_CACHE") else Path.home() / ".cache" / "mcrt"
    return base / "clean_root"


def clean_root_tarball() -> Path:
    """The minbase root as a tarball, built once with mmdebstrap into the cache folder."""
    tar = _cache_dir() / f"{SUITE}-minbase.tar"
    if not tar.exists():
        _need("mmdebstrap (apt-get install mmdebstrap)", shutil.which("mmdebstrap") is not None)
        tar.parent.mkdir(parents=True, exist_ok=True)
        part = tar.with_suffix(".part.tar")
        r = subprocess.run(["mmdebstrap", "--quiet", "--variant=minbase", SUITE, str(part)], capture_output=True, text=True,
                           timeout=1800)
        assert r.returncode == 0, r.stderr[-3000:]
        part.rename(tar)
    return tar


class Limits:
    """Gradescope's limits as cgroups beside this process's own: ``memory`` bytes over all of a hand-in's processes
    and half a CPU (cgroup v2 memory.max and cpu.max, else v1 memory.limit_in_bytes and cpu.cfs_quota_us)."""

    def __init__(self, memory: int, cpu: float = 0.5):
        self.version, self.groups = None, {}
        lines = Path("/proc/self/cgroup").read_text().splitlines()
        own = {c: p for _, cs, p in (ln.split(":", 2) for ln in lines) for c in cs.split(",")}
        name = f"mcrt-image-test-{os.getpid()}"
        period = 100_000
        for mount in ("/sys/fs/cgroup", "/sys/fs/cgroup/unified"):
            ctl = Path(mount) / "cgroup.controllers"
            if "" in own and ctl.exists() and {"memory", "cpu"} <= set(ctl.read_text().split()):
                d = self._make(Path(mount) / own[""].lstrip("/") / name, {"memory.max": memory, "memory.swap.max": 0,
                                                                          "cpu.max": f"{int(cpu * period)} {period}"})
                if d is not None:
                    self.version, self.groups = 2, {"memory": d}
                    return
        if "memory" in own and "cpu" in own:
            mem = self._make(Path("/sys/fs/cgroup/memory") / own["memory"].lstrip("/") / name,
                             {"memory.limit_in_bytes": memory})
            cpu_dir = next((p for p in (Path("/sys/fs/cgroup/cpu"), Path("/sys/fs/cgroup/cpu,cpuacct")) if p.exists()), None)
            cpu_g = self._make(cpu_dir / own["cpu"].lstrip("/") / name, {
                "cpu.cfs_period_us": period, "cpu.cfs_quota_us": int(cpu * period)}) if cpu_dir else None
            if mem is not None and cpu_g is not None:
                self.version, self.groups = 1, {"memory": mem, "cpu": cpu_g}
            else:
                for d in (mem, cpu_g):
                    d and d.rmdir()

    @staticmethod
    def _make(d: Path, settings: dict) -> Path | None:
        try:
            d.mkdir()
        except OSError:
            return None
        try:
            for k, v in settings.items():
                if k == "memory.swap.max" and not (d / k).exists():
                    continue  # no swap accounting: nothing to switch off
                (d / k).write_text(str(v))
            return d
        except OSError:
            d.rmdir()
            return None

    def enter(self) -> None:
        """For preexec_fn: move the calling (child) process into the groups."""
        for d in self.groups.values():
            (d / "cgroup.procs").write_text(str(os.getpid()))

    def peak(self) -> int | None:
        f = self.groups["memory"] / ("memory.peak" if self.version == 2 else "memory.max_usage_in_bytes")
        return int(f.read_text()) if f.exists() else None

    def oom_kills(self) -> int:
        m = self.groups["memory"]
        text = (m / ("memory.events" if self.version == 2 else "memory.oom_control")).read_text()
        return int(dict(ln.split() for ln in text.splitlines()).get("oom_kill", 0))

    def reset(self) -> None:
        if self.version == 1:
            (self.groups["memory"] / "memory.max_usage_in_bytes").write_text("0")

    def remove(self) -> None:
        for d in self.groups.values():
            d.rmdir()


def _du(path: Path) -> int:
    return int(subprocess.run(["du", "-sxb", str(path)], capture_output=True, text=True, check=True).stdout.split()[0])


def _in_root(root: Path, script: str, timeout: float, cgroup: Limits | None = None) -> subprocess.CompletedProcess:
    """Run a bash script as root inside the clean root, a mount namespace's root (bubblewrap, all capabilities)."""
    env = {"PATH": PATH, "HOME": "/root", "LANG": "C.UTF-8", "PIP_CERT": "/etc/ssl/certs/host-ca.crt",
           "PIP_DEFAULT_TIMEOUT": "120"}
    cmd = ["bwrap", "--bind", str(root), "/", "--dev", "/dev", "--proc", "/proc", "--ro-bind", "/sys", "/sys",
           "--ro-bind", "/etc/resolv.conf", "/etc/resolv.conf", "--cap-add", "ALL",
           "--unshare-pid", "--unshare-ipc", "--unshare-uts", "--die-with-parent", "--chdir", "/autograder",
           "bash", "-c", script]
    return subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout,
                          preexec_fn=cgroup.enter if cgroup else None)


@pytest.fixture(scope="module")
def image(tmp_path_factory):
    """The clean root with the code-mode zip set up in it: (root path, cgroup, figures)."""
    _need("bubblewrap (apt-get install bubblewrap)", shutil.which("bwrap") is not None)
    _need("root (to unpack the Debian root and enter it)", os.geteuid() == 0)
    figures: dict[str, float] = {}
    t0 = time.perf_counter()
    tar = clean_root_tarball()
    figures["root_build_s"] = time.perf_counter() - t0
    # Not under pytest's tmp folder: a root of 2 GB should go when the test ends, not linger three runs.
    root = Path(tempfile.mkdtemp(prefix="mcrt-clean-root-"))
    cgroup = Limits(MEMORY)
    try:
        subprocess.run(["tar", "-xf", str(tar), "-C", str(root)], check=True)
        figures["base_bytes"] = _du(root)
        (root / "etc/ssl/certs").mkdir(parents=True, exist_ok=True)
        shutil.copy(CA, root / "etc/ssl/certs/host-ca.crt")
        tmp = tmp_path_factory.mktemp("clean_image")
        (tmp / "gs16.toml").write_text(ASSIGNMENT)
        zpath = tmp / "autograder.zip"
        r = subprocess.run([sys.executable, "-m", "mcrt.cli", "gradescope-zip", "--mode", "code", "--out", str(zpath),
                            str(tmp / "gs16.toml")], capture_output=True, text=True, timeout=600, cwd=tmp)
        assert r.returncode == 0, r.stdout + r.stderr
        src = root / "autograder" / "source"
        src.mkdir(parents=True)
        with zipfile.ZipFile(zpath) as z:
            for info in z.infolist():
                z.extract(info, src)
                os.chmod(src / info.filename, (info.external_attr >> 16) & 0o777)
        t1 = time.perf_counter()
        r = _in_root(root, "bash /autograder/source/setup.sh && cp /autograder/source/run_autograder /autograder/",
                     timeout=3600)
        figures["setup_s"] = time.perf_counter() - t1
        assert r.returncode == 0, r.stdout[-5000:] + r.stderr[-5000:]
        assert "ready" in r.stdout and "unprivileged uid (65534) can run" in r.stdout, r.stdout[-3000:]
        figures["image_bytes"] = _du(root)
        figures["venv_bytes"] = _du(root / "autograder" / "venv")
        figures["cache_bytes"] = _du(root / "autograder" / "cache")
        figures["apt_lists_files"] = len(list((root / "var/lib/apt/lists").glob("*_Packages*")))
        figures["apt_cache_debs"] = len(list((root / "var/cache/apt/archives").glob("*.deb")))
        yield root, cgroup, figures
    finally:
        shutil.rmtree(root, ignore_errors=True)
        cgroup.remove()
        for k, v in figures.items():
            shown = f"{v / 2**20:.0f} MiB" if k.endswith("bytes") else f"{v:.1f} s" if k.endswith("_s") else f"{v:g}"
            print(f"clean image: {k} = {shown}", file=sys.stderr)


def _grade(image, files: dict[str, bytes], mode: str) -> dict:
    root, cgroup, figures = image
    sub, res = root / "autograder" / "submission", root / "autograder" / "results"
    for d in (sub, res):
        shutil.rmtree(d, ignore_errors=True)
        d.mkdir()
    for name, content in files.items():
        (sub / name).write_bytes(content)
    (root / "autograder" / "source" / "mode").write_text(mode + "\n")
    _need("memory and cpu cgroups (v2 memory.max and cpu.max, or v1)", cgroup.version is not None)
    cgroup.reset()
    t0 = time.perf_counter()
    r = _in_root(root, "/autograder/run_autograder", timeout=900, cgroup=cgroup)
    took = time.perf_counter() - t0
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    assert cgroup.oom_kills() == 0, f"a process of the hand-in was killed at the {MEMORY >> 20} MiB limit"
    data = check_results(res / "results.json")
    data["_stdout"], data["_seconds"], data["_peak"] = r.stdout, took, cgroup.peak()
    print(f"clean image: graded {sorted(files) or 'nothing'} ({mode}) in {took:.1f} s, peak "
          f"{(data['_peak'] or 0) / 2**20:.0f} MiB (cgroup v{cgroup.version}): {data['score']:g}", file=sys.stderr)
    return data


def test_setup_leaves_no_apt_lists_cache_or_left_out_packages(image):
    root, _, figures = image
    assert figures["apt_lists_files"] == 0 and figures["apt_cache_debs"] == 0
    assert not (root / "root" / ".cache" / "pip").exists()
    site = next((root / "autograder" / "venv" / "lib").glob("python3*/site-packages"))
    names = {p.name.split("-")[0].lower() for p in site.glob("*.dist-info")}
    assert {"mcrt", "drjit", "mitsuba", "numpy"} <= names and not names & {"matplotlib", "dask", "pyoidn", "pytest"}, names
    assert (root / "usr" / "bin" / "bwrap").exists()


def test_student_code_runs_unprivileged_in_the_clean_image(image):
    imgs = {s: base64.b64encode(_render(64, 600 + s).mean.astype("<f4").tobytes()).decode() for s in (1, 2)}
    module = GOOD.replace("def sample_cosine_hemisphere(u1, u2):", PROBE) + f"\nIMAGES = {imgs!r}\n"
    data = _grade(image, {"tracer.py": module.encode()}, "code")
    assert data["tests"], data["output"] + data["_stdout"][-3000:]  # graded, not refused
    probe = next(t for t in data["tests"] if t["tags"] == ["sample_cosine_hemisphere"])
    assert "PROBE uid=" in probe["output"], probe["output"]
    uid = int(probe["output"].split("PROBE uid=")[1].split()[0])
    euid = int(probe["output"].split("euid=")[1].split()[0])
    assert uid != 0 and euid != 0, f"student code ran as root: {probe['output'][:400]}"
    assert "shadow=unreadable" in probe["output"], probe["output"][:400]
    print(f"clean image: student code ran as uid {uid}, euid {euid}; /etc/shadow unreadable", file=sys.stderr)
    others = [t for t in data["tests"] if t["tags"] != ["sample_cosine_hemisphere"]]
    assert others and all(t["score"] == t["max_score"] for t in others), [(t["name"], t["output"][:300]) for t in others]


def test_image_hand_ins_are_graded_in_the_clean_image(image, tmp_path):
    from mcrt.image_files import write_exr

    write_exr(tmp_path / "good.exr", _render(64, 11))
    write_exr(tmp_path / "biased.exr", _render(64, 12, mutants=("rr_no_divide",)))
    manifest = b"spp = 64\n"
    good = _grade(image, {"render.exr": (tmp_path / "good.exr").read_bytes(), "manifest.toml": manifest}, "image")
    assert good["score"] == good["max_score"] == 100, good["output"]
    bad = _grade(image, {"render.exr": (tmp_path / "biased.exr").read_bytes(), "manifest.toml": manifest}, "image")
    assert bad["score"] < 100 and "rr\\_no\\_divide" in bad["output"], bad["output"][:500]
    empty = _grade(image, {}, "image")
    assert empty["score"] == 0 and empty["tests"], empty
    assert any(t["status"] == "failed" and "**What to do:**" in t["output"] for t in empty["tests"])
