#!/usr/bin/env bash
# Installs what specula needs on Debian 12 (as root): lavapipe (Mesa's CPU Vulkan
# driver), the Vulkan loader, the Khronos validation layer, glslangValidator for the
# shader build, spirv-val for the shader tests, a C/C++ compiler and the Vulkan headers
# (the C host examples), and Rust (rustup) when
# no cargo is on the PATH. Only installs what is missing, so reruns are quick.
set -euo pipefail
packages=(mesa-vulkan-drivers libvulkan1 libvulkan-dev vulkan-validationlayers glslang-tools spirv-tools build-essential pkg-config ca-certificates curl)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
if ! command -v cargo >/dev/null 2>&1; then
  [ -f "$HOME/.cargo/env" ] || curl -sSf https://sh.rustup.rs | sh -s -- -y --profile minimal
  # shellcheck disable=SC1091
  . "$HOME/.cargo/env"
fi
