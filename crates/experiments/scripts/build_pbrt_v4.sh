#!/usr/bin/env bash
# Builds pbrt-v4 (CPU only) outside the repository, as a peer for the one-run peer script
# (issues 46 item 7 and 47 item 1). Nothing of it is committed here.
#
# Usage: build_pbrt_v4.sh [DIR]   (default $HOME/peers/pbrt-v4); prints the executable's path.
#
# Sources: pbrt-v4 and its twelve submodules are cloned from GitHub, or from local mirrors when
# MIRROR is set (a folder of OWNER+NAME/repo git directories, as the tool library's `fetch`
# leaves them). A submodule whose pinned commit the mirror lacks is checked out at the mirror's
# newest commit, and the script says so (seen: mmp/double-conversion and madler/zlib).
# Needs: cmake, a C++17 compiler, OpenGL and X11 headers (pbrt's CMake requires OpenGL and builds
# GLFW for its viewer even without a GPU): on Debian `apt-get install cmake libgl-dev libx11-dev
# libxrandr-dev libxinerama-dev libxcursor-dev libxi-dev libopenexr-dev`, installed here when absent
# (Debian's OpenEXR 3.1, which pbrt's CMake prefers to its submodule: a mirror may lack the
# submodule's generated dwaLookups.h). pbrt's own submodule-commit check needs git in CMake, which
# is disabled (CMAKE_DISABLE_FIND_PACKAGE_Git): this script checks the commits and says where it
# could not use the pinned one.
# PBRT_BUILD_NATIVE_EXECUTABLE is OFF so the binary compares with lt's portable build; JOBS
# (default: the core count) parallel compiles, run under `nice` so it can share a machine.
set -euo pipefail
dir=${1:-$HOME/peers/pbrt-v4}
jobs=${JOBS:-$(nproc)}
origin() { # OWNER/NAME → where to clone it from
  local m="${MIRROR:-}/${1/\//+}/repo"
  if [ -n "${MIRROR:-}" ] && [ -d "$m" ]; then echo "$m"; else echo "https://github.com/$1.git"; fi
}

# Checks out HEAD's files in the clone at $1 except blobs the source lacks; prints those paths.
checkout_present() {
  local missing
  missing=$(git -C "$1" ls-tree -r HEAD | awk '$2 == "blob" { print $3, $4 }' |
    while read -r blob path; do git -C "$1" cat-file -e "$blob" 2>/dev/null || echo "$path"; done)
  git -C "$1" ls-tree -r -z --name-only HEAD | { if [ -n "$missing" ]; then grep -z -v -x -F "$missing"; else cat; fi; } |
    xargs -0 -r git -C "$1" checkout -q HEAD --
  echo "$missing"
}

if ! command -v cmake >/dev/null || [ ! -e /usr/include/GL/gl.h ] || [ ! -e /usr/include/X11/extensions/Xrandr.h ] \
  || [ ! -e /usr/include/X11/extensions/Xinerama.h ] || [ ! -e /usr/include/X11/Xcursor/Xcursor.h ] \
  || [ ! -e /usr/include/X11/extensions/XInput2.h ] || [ ! -d /usr/include/OpenEXR ]; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get install -y -qq cmake libgl-dev libx11-dev libxrandr-dev libxinerama-dev libxcursor-dev libxi-dev libopenexr-dev >/dev/null
fi

if [ ! -d "$dir/src/.git" ]; then
  mkdir -p "$dir"
  git clone -q --no-checkout "$(origin mmp/pbrt-v4)" "$dir/src"
fi
cd "$dir/src"
# A mirror may hold a repository without its largest blobs. pbrt's two data tables are the ones
# seen missing; both feed only the `pmj02bn` sampler (and 8-bit dithering, which EXR output does
# not do), so they are replaced by zero-filled tables of the declared shape — any use would show
# as a broken image, never as a subtly different one — and the peer runs name their sampler
# (`zsobol`, pbrt's default, reads neither). Any other missing file is an error.
missing=$(checkout_present .)
for path in $missing; do
  case "$path" in
  src/pbrt/util/bluenoise.cpp | src/pbrt/util/pmj02tables.cpp) ;;
  *) echo "build_pbrt_v4.sh: $path is missing from $(origin mmp/pbrt-v4)" >&2; exit 1 ;;
  esac
done
for path in $missing; do
  echo "build_pbrt_v4.sh: $path missing from the mirror: zero-filled stand-in (pmj02bn sampler unusable)" >&2
  case "$path" in
  */bluenoise.cpp) printf '%s\n' '#include <pbrt/util/bluenoise.h>' 'namespace pbrt {' \
    '// Stand-in written by build_pbrt_v4.sh: the real table was not available.' \
    'PBRT_CONST uint16_t BlueNoiseTextures[NumBlueNoiseTextures][BlueNoiseResolution][BlueNoiseResolution] = {};' \
    '}' >"$path" ;;
  */pmj02tables.cpp) printf '%s\n' '#include <pbrt/util/pmj02tables.h>' 'namespace pbrt {' \
    '// Stand-in written by build_pbrt_v4.sh: the real table was not available.' \
    'PBRT_CONST uint32_t pmj02bnSamples[nPMJ02bnSets][nPMJ02bnSamples][2] = {};' \
    '}' >"$path" ;;
  esac
done
echo "pbrt-v4 at $(git rev-parse --short HEAD)" >&2
# Each submodule: its URL from .gitmodules, its pinned commit from the tree.
git ls-tree HEAD src/ext/ | awk '$2 == "commit" { print $3, $4 }' | while read -r commit path; do
  url=$(git config -f .gitmodules "submodule.$path.url")
  repo=$(echo "$url" | sed 's|https://github.com/||; s|\.git$||')
  if [ ! -e "$path/.git" ]; then
    rm -rf "$path"
    git clone -q --no-checkout "$(origin "$repo")" "$path"
    if git -C "$path" cat-file -e "$commit^{commit}" 2>/dev/null; then
      git -C "$path" update-ref --no-deref HEAD "$commit"
    else
      echo "build_pbrt_v4.sh: $path: pinned $commit not in $(origin "$repo"); using $(git -C "$path" rev-parse --short HEAD)" >&2
    fi
    # Files a mirror lacks (seen: double-conversion's tests) are left out; the build says if it needs one.
    for f in $(checkout_present "$path"); do echo "build_pbrt_v4.sh: $path/$f missing, left out" >&2; done
  fi
done

mkdir -p "$dir/build"
cd "$dir/build"
if [ ! -e CMakeCache.txt ]; then
  cmake ../src -DCMAKE_BUILD_TYPE=Release -DPBRT_BUILD_NATIVE_EXECUTABLE=OFF \
    -DGLFW_BUILD_WAYLAND=OFF -DGLFW_BUILD_X11=ON -DCMAKE_DISABLE_FIND_PACKAGE_Git=TRUE -DBUILD_TESTING=OFF >"$dir/cmake.log" 2>&1 ||
    { tail -30 "$dir/cmake.log" >&2; exit 1; }
fi
nice -n 19 cmake --build . --target pbrt_exe -j "$jobs" >"$dir/build.log" 2>&1 ||
  { tail -30 "$dir/build.log" >&2; exit 1; }
echo "$dir/build/pbrt"
