#!/bin/sh
# quickstart.sh        install what is missing (Debian 12), build, run nbt-gen's default scene,
#                      render the demo (nbt-demo.png) and a render seen through fog (nbt-scatter.png)
# quickstart.sh check  the same set-up (warnings are errors), then the whole test suite
set -eu
cd "$(dirname "$0")"
mode=${1:-run}
case $mode in run|check) ;; *) echo "usage: ./quickstart.sh [check]" >&2; exit 2 ;; esac

PKGS="build-essential autoconf automake libtool pkg-config libgsl-dev libfftw3-dev libopenexr-dev openexr libpng-dev libceres-dev libeigen3-dev libgoogle-glog-dev libopenvdb-dev libboost-dev libegl-dev libopengl-dev libegl-mesa0 libgl1-mesa-dri glslang-tools spirv-cross glslc python3-numpy libopenmpi-dev openmpi-bin clang libclang-rt-14-dev"
# the suite also checks the EXR outputs in OpenImageIO and Blender and runs the Blender add-on headless
[ "$mode" = check ] && PKGS="$PKGS openimageio-tools blender zip"
missing=""
for p in $PKGS; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
  if [ "$(id -u)" -ne 0 ]; then
    echo "quickstart: missing Debian packages:$missing -- run as root, or: sudo apt-get install$missing" >&2
    exit 1
  fi
  echo "quickstart: installing$missing"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $missing >/dev/null
fi

jobs=$(nproc 2>/dev/null || echo 2)
[ -x configure ] || autoreconf -fi
flags=""
[ "$mode" = check ] && flags="--enable-werror --with-ceres --with-gl --with-openvdb --with-mpi"
./configure -q $flags ${NBT_CONFIGURE_FLAGS:-}
make -j"$jobs"

if [ "$mode" = run ]; then
  ./nbt-gen
  echo "quickstart: tables and previews are in ./nbt-tables/"
  if [ -x ./nbt-demo ]; then
    ./nbt-demo nbt-demo.png && echo "quickstart: the demo render (shaders + tables) is ./nbt-demo.png"
  fi
  # screen-space multiple scattering of a generated render (RGB + planar Z, as Blender writes it)
  ./nbt-scatter scene layers -o nbt-scatter-in.exr
  ./nbt-scatter nbt-scatter-in.exr -o nbt-scatter.exr --fov-y 40 --sigma-t 0.25 --albedo 0.95 --phase hg:g=0.9 \
    --quantize 64
  echo "quickstart: a render seen through fog (multiple scattering) is ./nbt-scatter.png"
  exit 0
fi

status=0
make -j"$jobs" check || status=$?
# a failing program's failed checks (CI shows only the end of the output)
[ $status -eq 0 ] || grep -H "^FAIL: " tests/*.log examples/*.log 2>/dev/null | head -40
# one plain line over all test programs (each prints "N passed, M failed")
cat tests/*.log 2>/dev/null | awk '/^[0-9]+ passed, [0-9]+ failed$/ { p += $1; f += $3 }
  END { printf "%d passed, %d failed\n", p, f }'
exit $status
