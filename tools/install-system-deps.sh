#!/usr/bin/env bash
# Debian packages the Python wheels need at run time:
#   open3d-cpu: libusb-1.0-0, libgl1, libegl1;  gmsh: libglu1-mesa, libxcursor1, libxft2, libxinerama1.
#   tests/web/test_browser.py: chromium (driven by Playwright with executable_path; no playwright install).
# Installs only what is missing; uses sudo when not root.
set -euo pipefail
packages=(libusb-1.0-0 libgl1 libegl1 libglu1-mesa libxcursor1 libxft2 libxinerama1 chromium)
missing=()
for package in "${packages[@]}"; do
    dpkg -s "$package" >/dev/null 2>&1 || missing+=("$package")
done
[ ${#missing[@]} -eq 0 ] && exit 0
as_root=()
[ "$(id -u)" -ne 0 ] && as_root=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get install -y -q "${missing[@]}" \
    || { "${as_root[@]}" apt-get update -q && "${as_root[@]}" apt-get install -y -q "${missing[@]}"; }
