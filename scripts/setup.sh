#!/usr/bin/env bash
# catgraph's one set-up script: installs the Debian packages the project needs
# when they are missing, configures and builds, then runs the main job or the
# test suite.
#
#   scripts/setup.sh demo    install, build, run the main job (README command 1)
#   scripts/setup.sh test    install, build, run the whole test suite, install
#                            catgraph into a prefix and build and run
#                            examples/ against it, then build the suite with
#                            clang under AddressSanitizer + UBSan and run it
#                            again, then every fuzz target for 30 s
#                            (README command 2; docs/fuzzing.md)
#   scripts/setup.sh build   install and build only
#
# Idempotent; works as root or through sudo. Environment: CATGRAPH_JOBS (build
# parallelism, default 2), CATGRAPH_BUILD_DIR (default build).
set -euo pipefail

mode="${1:-demo}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
jobs="${CATGRAPH_JOBS:-2}"
build_dir="${CATGRAPH_BUILD_DIR:-$root/build}"

case "$mode" in
  demo|test|build) ;;
  *) echo "usage: scripts/setup.sh [demo|test|build]" >&2; exit 2 ;;
esac

install_missing_packages() {
  local missing=()
  while read -r package; do
    [[ -z "$package" || "$package" == \#* ]] && continue
    if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$package")
    fi
  done < "$root/scripts/packages.txt"
  if (( ${#missing[@]} == 0 )); then
    echo "setup: all Debian packages present"
    return
  fi
  local sudo=()
  if (( EUID != 0 )); then
    if ! command -v sudo >/dev/null; then
      echo "setup: need root or sudo to install: ${missing[*]}" >&2
      exit 1
    fi
    sudo=(sudo)
  fi
  echo "setup: installing ${missing[*]}"
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive \
    apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# step TEXT: says what comes next and how long the script has run.
step() { echo "setup: $1 (${SECONDS} s in)"; }

# configure_and_build BUILD_DIR [extra cmake arguments...]
# A new folder is configured for Ninja, which starts compiling a target while
# the libraries it links are still being built; a folder configured earlier
# keeps its generator.
configure_and_build() {
  local dir="$1"; shift
  local generator=()
  [[ -f "$dir/CMakeCache.txt" ]] || generator=(-G Ninja)
  cmake -S "$root" -B "$dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DCATGRAPH_WERROR=ON "$@" >/dev/null
  cmake --build "$dir" -j "$jobs"
}

install_missing_packages
step "release build"
configure_and_build "$build_dir"
# `import catgraph` for this user: the built package linked into Debian
# Python's user site-packages (as `pip install -e` would; a rebuild updates
# it in place).
user_site="$(/usr/bin/python3 -m site --user-site)"
mkdir -p "$user_site"
ln -sfn "$build_dir/python/catgraph" "$user_site/catgraph"
echo "setup: python3 can import catgraph ($user_site/catgraph -> $build_dir/python/catgraph)"

case "$mode" in
  build) ;;
  demo)
    # The main job: simulate office-change (furniture moved before the second
    # traversal) and map it end to end: CAT-Graph and CAT-Graph+ closures,
    # robust solve with the closure hierarchy, corrected map and pictures.
    "$build_dir/apps/catgraph" demo -o "$root/out/demo"
    ;;
  test)
    step "the suite"
    ctest --test-dir "$build_dir" -j "$jobs" --output-on-failure
    step "examples/ built against the installed package"
    bash "$root/scripts/examples.sh" "$build_dir"
    # One clang build serves both: the suite under the sanitizers and the
    # libFuzzer targets (CATGRAPH_FUZZ implies CATGRAPH_SANITIZE).
    step "the suite again under AddressSanitizer + UndefinedBehaviorSanitizer (clang): build"
    configure_and_build "$build_dir-sanitize" -DCMAKE_CXX_COMPILER=clang++-14 -DCATGRAPH_FUZZ=ON \
      -DCATGRAPH_BUILD_BENCH=OFF -DCATGRAPH_BUILD_PYTHON=OFF
    # The sanitizer build registers every case but the [slow] ones
    # (tests/CMakeLists.txt); the release pass above ran those.
    step "the suite under the sanitizers"
    ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      ctest --test-dir "$build_dir-sanitize" -j "$jobs" --output-on-failure
    # A fixed seed, so that a run's verdict does not depend on luck.
    step "every fuzz target for 30 s"
    FUZZ_BUILD_DIR="$build_dir-sanitize" FUZZ_SEED=1 bash "$root/scripts/fuzz.sh" 30
    ;;
esac
step "done"
