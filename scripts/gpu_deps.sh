# Sourced by the GPU-machine scripts. The GPU machine lacks some of Debian's -dev packages (zstd's
# headers, ZFP, fpzip); unpacked into gpu-deps/ (git-ignored, carried) they are found from here:
#   for p in libzstd-dev libzstd1 libzfp1 libzfp-dev libfpzip1 libfpzip-dev; do apt-get download $p; done
#   for f in *.deb; do dpkg -x $f gpu-deps; done
afam_deps="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/gpu-deps/usr"
if [ -d "$afam_deps" ]; then
  export CMAKE_PREFIX_PATH="$afam_deps${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
  export LD_LIBRARY_PATH="$afam_deps/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  export CPATH="$afam_deps/include${CPATH:+:$CPATH}"
fi
