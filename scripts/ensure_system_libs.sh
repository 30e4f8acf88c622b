#!/usr/bin/env bash
# Installs the Debian libraries sortbot needs at run time, only those missing:
# EGL/OSMesa for headless MuJoCo rendering, GL/GLib for OpenCV, libusb for Open3D,
# FFmpeg 5 libraries so torchcodec decodes LeRobot videos (else lerobot falls back to PyAV, noisily).
set -euo pipefail
needed=(libegl1 libegl-mesa0 libgl1-mesa-dri libosmesa6 libgl1 libglib2.0-0 libusb-1.0-0
        libavutil57 libavcodec59 libavformat59 libavdevice59 libavfilter8 libswscale6 libswresample4)
missing=()
for pkg in "${needed[@]}"; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
[ ${#missing[@]} -eq 0 ] && exit 0
echo "sortbot: installing system libraries: ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  SUDO=sudo; command -v sudo >/dev/null || { echo "sortbot: not root and no sudo: install ${missing[*]} yourself" >&2; exit 1; }
else
  SUDO=
fi
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
