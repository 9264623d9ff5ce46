# Sourced by the other scripts: installs the Debian 12 packages the build and
# the tests need, only those missing, with sudo when not root.
# shellcheck shell=bash

TSMH_PACKAGES=(
  build-essential cmake pkg-config dpkg-dev
  libeigen3-dev libyaml-cpp-dev nlohmann-json3-dev libcli11-dev libnlopt-cxx-dev
  liblcm-dev liblcm-bin libglib2.0-dev iproute2 libsodium-dev
  libhidapi-dev libusb-1.0-0-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  gnuplot-nox python3 help2man
  default-jdk-headless liblcm-java libjchart2d-java
)

tsmh_missing_packages() {
  local p missing=()
  for p in "$@"; do
    if [ "$(dpkg-query -W -f='${db:Status-Abbrev}' "$p" 2>/dev/null | cut -c1-2)" != "ii" ]; then
      missing+=("$p")
    fi
  done
  echo "${missing[@]}"
}

tsmh_install_packages() {
  local missing
  missing=$(tsmh_missing_packages "$@")
  [ -z "$missing" ] && return 0
  echo "tsm-haptics: installing missing Debian packages: $missing" >&2
  local sudo=()
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "error: need root or sudo to install: $missing" >&2; return 1; }
    sudo=(sudo)
  fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo[@]}" apt-get update -qq || { echo "error: apt-get update failed" >&2; return 1; }
  # shellcheck disable=SC2086
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends $missing >&2 ||
    { echo "error: apt-get install failed for: $missing" >&2; return 1; }
}
