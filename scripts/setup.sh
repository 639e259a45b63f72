#!/usr/bin/env bash
# Installs the system packages quadray needs on Debian/Ubuntu: the Vulkan loader and Mesa's
# software Vulkan driver (lavapipe), so the GPU techniques run without a GPU; Xvfb and the X11
# libraries winit opens, so the viewer's test runs in a virtual display. Idempotent; it only
# calls apt-get when something is missing. Pass --embree to also install Embree 3 for the
# `embree` feature of the shadow benchmarks.
set -euo pipefail
pkgs=(libvulkan1 mesa-vulkan-drivers xvfb libx11-xcb1 libxcursor1 libxrandr2 libxi6 libxkbcommon-x11-0)
[[ "${1:-}" == "--embree" ]] && pkgs+=(libembree-dev)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  sudo=""
  [[ $(id -u) -ne 0 ]] && sudo="sudo"
  echo "setup: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}"
fi
