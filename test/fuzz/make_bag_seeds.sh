#!/usr/bin/env bash
# Writes the seed bags of fuzz_bag (test/fuzz/corpus/bag/seed_*): small valid
# bags from synthesize_bag (road at 50 Hz, a few samples), lz4/bz2-compressed
# and truncated copies. Run by hand after building the catkin workspace:
#   test/fuzz/make_bag_seeds.sh [PATH/TO/synthesize_bag]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
tool=${1:-$root/.build/catkin_ws/devel/lib/pc_ekf/synthesize_bag}
out=$here/corpus/bag
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$out"

# speed_bump.yaml with few samples over a short time (small bags); without
# the node-only section, which the bag is independent of.
config() {  # SAMPLES DURATION CHANNELS
  sed -e '/^node:/,/^[a-z]/ { /^node:/d; /^[ #]/d; }' -e "/^sampling:/,/^[a-z]/ s/^  samples: .*/  samples: $1/" \
      -e "/^sampling:/,/^[a-z]/ s/^  duration: .*/  duration: $2/" \
      -e "/^measurement:/,/^[a-z]/ s/^  channels: .*/  channels: $3/" \
      "$root/config/speed_bump.yaml" >"$tmp/c.yaml"
}

config 3 0.3 "[u1, u2, v1, v2]"
"$tool" --config "$tmp/c.yaml" --output "$out/seed_bump3.bag" --road-rate 50
config 2 0.1 "[u1, v2]"
"$tool" --config "$tmp/c.yaml" --output "$out/seed_bump2_u1v2.bag" --road-rate 50 \
  --start-time 5 --seed 4
# Compressed chunks (rosbag compress: Python rosbag, /usr/bin first on PATH).
for c in lz4 bz2; do
  cp "$out/seed_bump3.bag" "$tmp/$c.bag"
  PATH=/usr/bin:$PATH rosbag compress "--$c" -q "$tmp/$c.bag"
  cp "$tmp/$c.bag" "$out/seed_bump3_$c.bag"
done
# Truncated: inside the file header record, in the first chunk, before the index.
size=$(stat -c %s "$out/seed_bump3.bag")
for cut in 13 100 4200 $((size / 2)) $((size - 40)); do
  [ "$cut" -lt "$size" ] && head -c "$cut" "$out/seed_bump3.bag" >"$out/seed_bump3_truncated_$cut.bag"
done
ls -l "$out"
