# Shared by the benchmark scripts (sourced): the release binary and the frame's GPU ms from
# the CLI's per-pass table.
bin=./target/release/specula
frame_ms() { grep -E '^frame +[0-9.]+ +[0-9.]+$' | awk '{print $2}'; }
