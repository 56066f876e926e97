# Source on a lent GPU machine, from the repository root, with .whl/ and .gl/ carried
# (eval/gqcnn/gpu_wheels.sh made them): the EGL loaders unpacked into /, each wheel unpacked into
# /tmp/site, suctionbench installed in development mode without touching the image's packages.
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
export MUJOCO_GL=egl PYTHONUNBUFFERED=1
mkdir -p /tmp/site
for w in .whl/*.whl; do python3 -m zipfile -e "$w" /tmp/site; done
export PYTHONPATH=/tmp/site
# development mode: suctionbench.assets is the repository's assets/ folder (pyproject's package-dir)
python3 -m pip install -q --no-deps --no-build-isolation --no-index -e .
python3 -c "import mujoco, trimesh, embreex, suctionbench.cli; print('setup: mujoco', mujoco.__version__)"
