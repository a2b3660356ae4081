#!/usr/bin/env python3
"""Installs Intel Open Image Denoise 2.5.1 (OIDN, Apache-2.0) for `rt-gpu --denoise`.

Debian has no OIDN package and Intel's release archives are not on the package registries this
project's machines reach, so this takes OIDN's own shared libraries from the PyPI wheel
`pyoidn` 2.5.1.0 (which ships them unchanged): it downloads the pinned wheel with pip, checks its
sha256, and unpacks only the CPU device's libraries (OIDN, its core with the trained weights,
its CPU device, TBB) into rt-gpu's cache, where rt-gpu looks for them
(`src/denoise/library.rs`): $XDG_CACHE_HOME/rt-gpu/oidn-2.5.1, else ~/.cache/rt-gpu/oidn-2.5.1.
The licence texts go beside them. Nothing is installed system-wide; running it again does
nothing once the libraries are in place.

Usage: python3 scripts/install-oidn.py [--dest DIR] [--wheel FILE.whl]
"""

import argparse
import hashlib
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import venv
import zipfile
from pathlib import Path

VERSION = "2.5.1"
WHEEL = "pyoidn-2.5.1.0-py3-none-manylinux2014_x86_64.whl"
SHA256 = "32ad13368f8de1ef63001942ad05b02a00cd732d1206d97f352d3a3f606d823e"
# The CPU device's libraries, as the wheel names them (its copies of the symlinks are whole files).
LIBRARIES = [
    "libOpenImageDenoise.so.2.5.1",
    "libOpenImageDenoise_core.so.2.5.1",
    "libOpenImageDenoise_device_cpu.so.2.5.1",
    "libtbb.so.12",
]
# The names the loader and OIDN's RPATH ($ORIGIN/../lib) ask for, as links.
LINKS = {"libOpenImageDenoise.so.2": "libOpenImageDenoise.so.2.5.1"}

NOTICE = """These libraries are Intel Open Image Denoise 2.5.1 and oneAPI Threading Building Blocks,
unmodified, as the PyPI wheel pyoidn 2.5.1.0 ships them (sha256 {sha}).

Intel Open Image Denoise: Copyright 2018 Intel Corporation. Licensed under the Apache License,
Version 2.0 (LICENSE-Apache-2.0). https://github.com/RenderKit/oidn
oneAPI Threading Building Blocks (libtbb.so.12): Copyright 2005 Intel Corporation. Licensed under
the Apache License, Version 2.0 (LICENSE-Apache-2.0). https://github.com/uxlfoundation/oneTBB
The pyoidn binding's own licence (MIT) is LICENSE-pyoidn.
"""


def default_dest() -> Path:
    cache = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(cache) / "rt-gpu" / f"oidn-{VERSION}"


def sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def pip_download(into: Path) -> Path:
    """The pinned wheel, downloaded by pip (this Python's, else a throwaway environment's)."""
    args = ["download", "--quiet", "--no-deps", "--only-binary=:all:", "--dest", str(into),
            "--platform", "manylinux2014_x86_64",
            f"pyoidn=={VERSION}.0"]
    pip = [sys.executable, "-m", "pip"]
    if subprocess.run(pip + ["--version"], capture_output=True).returncode != 0:
        env = into / "venv"
        venv.create(env, with_pip=True)
        pip = [str(env / "bin" / "python"), "-m", "pip"]
    subprocess.run(pip + args, check=True)
    wheel = into / WHEEL
    if not wheel.exists():
        raise RuntimeError(f"pip downloaded no {WHEEL}")
    return wheel


def install(wheel: Path, dest: Path) -> None:
    got = sha256(wheel)
    if got != SHA256:
        sys.exit(f"install-oidn: {wheel} has sha256 {got}, expected {SHA256}")
    staging = Path(tempfile.mkdtemp(prefix=".oidn-", dir=dest.parent))
    staging.chmod(0o755)
    try:
        lib = staging / "lib"
        lib.mkdir()
        with zipfile.ZipFile(wheel) as archive:
            for name in LIBRARIES:
                target = lib / name
                with archive.open(f"pyoidn/oidn/lib/{name}") as src, open(target, "wb") as out:
                    shutil.copyfileobj(src, out)
                target.chmod(0o755)
            with archive.open(f"pyoidn-{VERSION}.0.dist-info/licenses/LICENSE") as src:
                (staging / "LICENSE-pyoidn").write_bytes(src.read())
        for link, target in LINKS.items():
            (lib / link).symlink_to(target)
        apache = Path("/usr/share/common-licenses/Apache-2.0")
        if apache.exists():
            shutil.copyfile(apache, staging / "LICENSE-Apache-2.0")
        else:
            (staging / "LICENSE-Apache-2.0").write_text(
                "Apache License, Version 2.0: https://www.apache.org/licenses/LICENSE-2.0.txt\n")
        (staging / "NOTICE").write_text(NOTICE.format(sha=SHA256))
        # Swapped in by renames: an rt-gpu loading it meanwhile sees the old copy or the new.
        old = None
        if dest.exists():
            old = Path(tempfile.mkdtemp(prefix=".oidn-old-", dir=dest.parent))
            dest.rename(old / "oidn")
        staging.rename(dest)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    finally:
        if staging.exists():
            shutil.rmtree(staging)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dest", type=Path, default=default_dest(),
                        help="where to unpack (default: %(default)s)")
    parser.add_argument("--wheel", type=Path, help="a downloaded copy of " + WHEEL)
    args = parser.parse_args()
    if sys.platform != "linux" or platform.machine() not in ("x86_64", "AMD64"):
        sys.exit("install-oidn: this wheel is Linux x86-64's; elsewhere install OIDN 2 from "
                 "https://github.com/RenderKit/oidn/releases and set OIDN_DIR")
    dest = args.dest
    wanted = [dest / "NOTICE"] + [dest / "lib" / name for name in [*LIBRARIES, *LINKS]]
    if all(path.exists() for path in wanted):
        print(f"install-oidn: OIDN {VERSION} is already in {dest}")
        return
    try:
        dest.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory() as scratch:
            wheel = args.wheel or pip_download(Path(scratch))
            install(wheel, dest)
    except (OSError, RuntimeError, subprocess.CalledProcessError, zipfile.BadZipFile, KeyError) as e:
        sys.exit(f"install-oidn: {e}")
    print(f"install-oidn: OIDN {VERSION} (CPU device) installed in {dest}")


if __name__ == "__main__":
    main()
