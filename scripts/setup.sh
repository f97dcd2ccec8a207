#!/usr/bin/env bash
# Install what ejsgen and its test suite need on a fresh Debian machine with Python 3.11:
# Debian's chromium (for the real-browser tests) and the package with its test extras.
set -euo pipefail
cd "$(dirname "$0")/.."
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
need=()
# Debian's Chromium for the real-browser tests (never a browser download)
[ -x /usr/bin/chromium ] || need+=(chromium)
# Mesa's EGL and software OpenGL for the optional GL renderer (moderngl) and its tests;
# only when missing, so present packages are not upgraded
if ! ldconfig -p | grep -q 'libEGL_mesa.so.0' || ! ls /usr/lib/*/dri/swrast_dri.so >/dev/null 2>&1; then
  need+=(libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri)
fi
# a C compiler: the build compiles FMUs kept as C sources (lab 8's joint drives, tests/fmu)
command -v cc >/dev/null 2>&1 || need+=(gcc libc6-dev)
# Debian's nginx for the test of the class-across-machines recipe (specs/deploy.md); only the
# binary is used, with a config in a temporary folder on loopback ports
[ -x /usr/sbin/nginx ] || need+=(nginx)
# Debian's mosquitto MQTT broker for the remote-laboratory tests (tests/plant); only the binary
# is used, started by the tests with a config in a temporary folder on loopback ports
[ -x /usr/sbin/mosquitto ] || need+=(mosquitto)
# Debian's bubblewrap: ejsgen sweep --sandbox and examples/grading/grade.py build and run each hand-in in its sandbox
# (read-only file system but its own folder, no network); only when missing
command -v bwrap >/dev/null 2>&1 || need+=(bubblewrap)
if [ ${#need[@]} -gt 0 ]; then
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need[@]}" >/dev/null
fi
# The package itself: built and installed as a wheel, as students get it (CI tests that), or
# with --editable for development in this checkout.
if [ "${1:-}" = "--editable" ]; then
  python3 -m pip install -q --disable-pip-version-check -e ".[test]"
else
  python3 -m pip install -q --disable-pip-version-check ".[test]"
  # replaces an earlier editable install of this checkout, if any
  python3 -m pip install -q --disable-pip-version-check --force-reinstall --no-deps .
fi
