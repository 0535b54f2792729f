#!/usr/bin/env bash
# Installs what specula needs on Debian 12 (as root): lavapipe (Mesa's CPU Vulkan
# driver, Mesa 25 from bookworm-backports), the Vulkan loader, the Khronos validation layer, glslangValidator for the
# shader build, spirv-val for the shader tests, a C/C++ compiler and the Vulkan headers
# (the C host examples), an X server without a screen with the X libraries winit loads
# (`specula view`: xvfb-run runs it headless in the tests), and Rust (rustup) when
# no cargo is on the PATH. Only installs what is missing, so reruns are quick.
set -euo pipefail
packages=(mesa-vulkan-drivers libvulkan1 libvulkan-dev vulkan-validationlayers glslang-tools spirv-tools build-essential pkg-config ca-certificates curl
  xvfb xauth libx11-xcb1 libxcursor1 libxrandr2 libxi6 libxkbcommon-x11-0)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# lavapipe from Mesa 25 (Vulkan 1.4 with VK_KHR_acceleration_structure and VK_KHR_ray_query:
# the `ray-query` method) comes from Debian 12's bookworm-backports suite, added as an apt
# source at its default (low) priority so that only packages asked for with
# `-t bookworm-backports` come from it. Besides mesa-vulkan-drivers it pulls in Mesa's
# shared gallium library (mesa-libgallium) and libdrm 2.4.123 (libdrm2, libdrm-common,
# libdrm-amdgpu1 and the other libdrm-* driver libraries present).
backports=/etc/apt/sources.list.d/specula-bookworm-backports.sources
mesa_version=$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)
export DEBIAN_FRONTEND=noninteractive
if [ ${#missing[@]} -gt 0 ] || ! dpkg --compare-versions "${mesa_version:-0}" ge 25; then
  if [ ! -f "$backports" ] && ! grep -rqs "bookworm-backports" /etc/apt/sources.list /etc/apt/sources.list.d/; then
    printf 'Types: deb\nURIs: http://deb.debian.org/debian\nSuites: bookworm-backports\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' >"$backports"
  fi
  apt-get update -qq
  if [ ${#missing[@]} -gt 0 ]; then
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  fi
  apt-get install -y -qq --no-install-recommends -t bookworm-backports mesa-vulkan-drivers >/dev/null
fi
if ! command -v cargo >/dev/null 2>&1; then
  [ -f "$HOME/.cargo/env" ] || curl -sSf https://sh.rustup.rs | sh -s -- -y --profile minimal
  # shellcheck disable=SC1091
  . "$HOME/.cargo/env"
fi
