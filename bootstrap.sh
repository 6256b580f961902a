#!/usr/bin/env bash
# Set up everything vibrofeed needs on Debian 12, then run a job:
#
#   bash bootstrap.sh demo       # install, then run the main job (the default)
#   bash bootstrap.sh test       # install, then run the default test suite (CTest)
#   bash bootstrap.sh validate   # install, then run the long validation cases
#   bash bootstrap.sh setup      # install only (what demo needs)
#
# Installs what the job needs and no more. Every job: Debian packages (LIGGGHTS,
# Open MPI, Python, compilers, ffmpeg) and a virtual environment at .venv with
# vibrofeed installed editable (mpi4py built against the system Open MPI, the
# abort shim built into the package). `test` and `validate` add the test tools:
# TEST_APT_PACKAGES, the Python extra `test`, and the CMake build directory build/.
# Every step is skipped when already done, so a second call takes seconds.
set -euo pipefail

cd "$(dirname "$0")"
ROOT=$PWD
JOB=${1:-demo}
case "$JOB" in demo|test|validate|setup) ;; *)
  echo "usage: bash bootstrap.sh [demo|test|validate|setup]" >&2; exit 2;;
esac

APT_PACKAGES=(liggghts libliggghts-dev openmpi-bin libopenmpi-dev
              python3 python3-venv python3-dev build-essential ca-certificates
              libegl1 libgl1-mesa-dri  # off-screen pictures: VTK's EGL window, Mesa software GL
              ffmpeg)                  # movies: vibrofeed render -o RUN.mp4
# Only for the test suite (jobs test and validate); append what a test needs.
# pvpython is in python3-paraview, which paraview only recommends (and apt runs with
# --no-install-recommends): without it the ParaView test would skip (fail on CI).
TEST_APT_PACKAGES=(cmake
                   paraview python3-paraview xvfb)  # pvpython under xvfb-run checks the ParaView export
WITH_TESTS=0
[[ $JOB == test || $JOB == validate ]] && WITH_TESTS=1
((WITH_TESTS)) && APT_PACKAGES+=("${TEST_APT_PACKAGES[@]}")

say() { printf '\033[1m[bootstrap]\033[0m %s\n' "$*"; }

# Installer output (apt, pip, cmake) goes to setup.log; it is shown only when a
# step fails, so the few lines a newcomer needs are not buried in it.
LOG="$ROOT/setup.log"
: > "$LOG"
quietly() {
  if ! "$@" >> "$LOG" 2>&1; then
    echo "bootstrap: '$*' failed; the last lines of $LOG:" >&2
    tail -n 40 "$LOG" >&2
    exit 1
  fi
}

# ------------------------------------------------------------ Debian packages
missing=()
for pkg in "${APT_PACKAGES[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null || true)
  [[ $status == "install ok installed" ]] || missing+=("$pkg")
done
if ((${#missing[@]})); then
  say "installing Debian packages: ${missing[*]}"
  SUDO=()
  if [[ $(id -u) -ne 0 ]]; then
    command -v sudo >/dev/null || { echo "need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
    SUDO=(sudo)
  fi
  export DEBIAN_FRONTEND=noninteractive
  quietly "${SUDO[@]}" apt-get update -q
  quietly "${SUDO[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# ------------------------------------------------------------ Python venv
PY=/usr/bin/python3   # Debian's Python: the one the system MPI and LIGGGHTS are built for
# The stamp holds what was installed: a hash of the files the install reads or
# builds, and the extras. A changed hash reinstalls with the extras already there;
# a job that needs the test extra adds it once.
STAMP=.venv/.vibrofeed-installed
HASH=$(cat pyproject.toml setup.py native/abort_flush.c | sha256sum | cut -d' ' -f1)
read -r had_hash had_extras 2>/dev/null < "$STAMP" || true
EXTRAS=${had_extras:-}
((WITH_TESTS)) && EXTRAS=test
if [[ ! -x .venv/bin/python ]]; then
  say "creating .venv"
  quietly "$PY" -m venv .venv
fi
SHIM=vibrofeed/engine/libvibrofeed_abortflush.so  # the editable install builds it in place
if [[ ${had_hash:-} != "$HASH" || ${had_extras:-} != "$EXTRAS" || ! -f $SHIM ]]; then
  say "installing vibrofeed${EXTRAS:+ with its $EXTRAS tools} into .venv (mpi4py is compiled the first time: a few minutes)"
  quietly .venv/bin/python -m pip install --upgrade pip
  # mpi4py from source, against the system Open MPI that LIGGGHTS uses.
  quietly .venv/bin/python -m pip install --no-binary mpi4py -e ".${EXTRAS:+[$EXTRAS]}"
  echo "$HASH $EXTRAS" > "$STAMP"
fi

# ------------------------------------------------------------ CMake build dir (tests only)
if ((WITH_TESTS)); then
  if [[ ! -f build/CMakeCache.txt ]]; then
    say "configuring build/"
    quietly cmake -S . -B build -DPython3_EXECUTABLE="$ROOT/.venv/bin/python"
  fi
  quietly cmake --build build
fi

# ------------------------------------------------------------ the job
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
case "$JOB" in
  demo)
    say "running the main job: a feeder line delivering 300 um parts one at a time (its feed rate, singulation, rejects)"
    .venv/bin/vibrofeed demo -o results ;;
  test)
    say "running the default test suite (ctest -LE slow)"
    ctest --test-dir build -LE slow --output-on-failure -j 2 ;;
  validate)
    say "running the validation cases (ctest -L validation)"
    ctest --test-dir build -L validation --output-on-failure ;;
  setup)
    say "ready: .venv/bin/vibrofeed --help (bash bootstrap.sh test adds the test tools)" ;;
esac
