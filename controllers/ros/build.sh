#!/usr/bin/env bash
# Build the thesis' catkin workspace (amr_idea_control, amr_idea_bringup: this folder is its src) with
# catkin_make against Debian's ROS 1 (install.sh installs it), into a cache folder keyed by the sources'
# hash: ${AMR_TWIN_CACHE_DIR:-~/.cache/amr-twin}/catkin/<hash> (a temporary folder when AMR_TWIN_CACHE_DIR
# is empty). Prints the devel space's setup.bash; `source` it to rosrun/roslaunch the packages:
#     source "$(bash controllers/ros/build.sh)" && roslaunch amr_idea_bringup amr_idea.launch ...
# The source tree is not written to. A second call with the same sources prints the same path at once.
set -euo pipefail
src="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
packages=(amr_idea_control amr_idea_bringup)
for tool in catkin_make /usr/bin/python3; do
    command -v "$tool" >/dev/null || { echo "error: $tool not found: install ROS 1 with bash $src/install.sh" >&2; exit 2; }
done
hash="$(cd "$src" && find "${packages[@]}" -type f -print0 | sort -z | xargs -0 sha256sum | sha256sum | cut -c1-16)"
if [ -n "${AMR_TWIN_CACHE_DIR-unset}" ] && [ "${AMR_TWIN_CACHE_DIR-unset}" != "unset" ]; then
    root="$AMR_TWIN_CACHE_DIR/catkin"
elif [ "${AMR_TWIN_CACHE_DIR-unset}" = "unset" ]; then
    root="$HOME/.cache/amr-twin/catkin"
else
    root="$(mktemp -d -t amr-twin-catkin-XXXXXX)"
fi
ws="$root/$hash"
mkdir -p "$root"
exec 9>"$root/.lock-$hash"
flock 9
if [ ! -f "$ws/.built" ]; then
    rm -rf "$ws"
    mkdir -p "$ws/src"
    for p in "${packages[@]}"; do ln -s "$src/$p" "$ws/src/$p"; done
    if ! (cd "$ws" && catkin_make -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCATKIN_ENABLE_TESTING=OFF \
            >"$ws/build.log" 2>&1); then
        grep -m1 -E "error|Error" "$ws/build.log" >&2 || tail -5 "$ws/build.log" >&2
        echo "error: catkin_make failed (log: $ws/build.log)" >&2
        exit 1
    fi
    touch "$ws/.built"
fi
echo "$ws/devel/setup.bash"
