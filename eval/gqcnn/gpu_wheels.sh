#!/usr/bin/env bash
# Prepare, on the development machine, what a lent GPU machine needs to run eval/gqcnn/gpu.sh: it
# has torch but none of the project's other dependencies, and no network. Writes .whl/ (cp312
# manylinux wheels at the versions of .venv; mujoco without its mujoco/experimental folder, 15 MB
# the project never imports, so the lease's 64 MiB working tree holds it) and .gl/ (the EGL loader
# packages MuJoCo's offscreen renderer needs). Both folders must be git-ignored (.git/info/exclude)
# and carried; eval/gqcnn/gpu_setup.sh installs them there.
set -euo pipefail
PIP=${PIP:-.venv/bin/pip}
names="trimesh embreex rtree manifold3d qpsolvers clarabel cffi pycparser tomli-w mujoco pyopengl glfw gymnasium
farama-notifications typer pydantic pydantic-core annotated-types typing-inspection mcap"
pins=()
for name in $names; do
  pins+=("$name==$($PIP show "$name" 2>/dev/null | sed -n 's/^Version: //p')")
done
rm -rf .whl && mkdir -p .whl
platforms=()
for p in manylinux_2_28_x86_64 manylinux_2_27_x86_64 manylinux_2_24_x86_64 manylinux_2_17_x86_64 \
    manylinux2014_x86_64 manylinux1_x86_64; do platforms+=(--platform "$p"); done
python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
  "${platforms[@]}" -d .whl "${pins[@]}"
python3 - <<'PY'
import glob, os, zipfile
(src,) = glob.glob(".whl/mujoco-*.whl")
with zipfile.ZipFile(src) as zi, zipfile.ZipFile(src + ".tmp", "w", zipfile.ZIP_DEFLATED) as zo:
    for item in zi.infolist():
        if not item.filename.startswith("mujoco/experimental/"):
            zo.writestr(item, zi.read(item.filename))
os.replace(src + ".tmp", src)
PY
rm -rf .gl && mkdir -p .gl /tmp/amd64/partial
o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
apt-get $o update >/dev/null
(cd .gl && apt-get $o download libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
du -sh .whl .gl
