#!/usr/bin/env bash
# Fetch the MuJoCo 3.17.0 shared library from the official `mujoco` PyPI wheel into
# third_party/mujoco/lib (git-ignored). Idempotent: does nothing when the library is there.
# Only `libmujoco.so.3.17.0` is extracted (about 7 MB, depends on libc/libm only).
set -euo pipefail

MUJOCO_VERSION="3.17.0"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
lib_dir="$root/third_party/mujoco/lib"
lib_file="$lib_dir/libmujoco.so.$MUJOCO_VERSION"

if [[ -f "$lib_file" && -L "$lib_dir/libmujoco.so" ]]; then
    exit 0
fi

python="${PYTHON:-$(command -v python3 || command -v python || true)}"
if [[ -z "$python" ]]; then
    echo "error: python3 with pip is needed to fetch the mujoco==$MUJOCO_VERSION wheel" >&2
    exit 1
fi

download="$(mktemp -d)"
trap 'rm -rf "$download"' EXIT
echo "fetching MuJoCo $MUJOCO_VERSION (PyPI wheel) ..." >&2
"$python" -m pip download --quiet --no-deps --only-binary=:all: \
    --dest "$download" "mujoco==$MUJOCO_VERSION" >&2

wheel="$(ls "$download"/mujoco-"$MUJOCO_VERSION"-*.whl | head -n 1)"
mkdir -p "$lib_dir"
"$python" - "$wheel" "$lib_file" <<'PY'
import shutil, sys, zipfile
wheel, dest = sys.argv[1], sys.argv[2]
with zipfile.ZipFile(wheel) as z, z.open("mujoco/" + dest.rsplit("/", 1)[-1]) as src, open(dest + ".part", "wb") as out:
    shutil.copyfileobj(src, out)
PY
mv "$lib_file.part" "$lib_file"
ln -sfn "libmujoco.so.$MUJOCO_VERSION" "$lib_dir/libmujoco.so"
echo "MuJoCo $MUJOCO_VERSION ready in $lib_dir" >&2
