#!/usr/bin/env bash
# Install Debian's ROS 1 for the twin's optional ROS 1 path (amr-twin run ... --ros1, the catkin workspace
# of this folder, the rosserial host): the packages of debian-packages.txt beside this script, with apt-get
# (as root, or through sudo). About 5 minutes and 1 GB on a fresh Debian 12. Exit 1 if apt-get fails.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
mapfile -t packages < <(grep -v '^#' "$here/debian-packages.txt")
sudo=""
if [ "$(id -u)" != "0" ] && command -v sudo >/dev/null 2>&1; then sudo="sudo"; fi
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${packages[@]}"
