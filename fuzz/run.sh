#!/bin/sh
# Runs every fuzz target for 1 M executions (or the targets given), each from the committed seeds
# (fuzz/corpus/TARGET, read only) with new inputs kept in fuzz/work/TARGET (ignored by git), and prints
# libFuzzer's final figures. Crashes, OOMs and timeouts land in fuzz/artifacts/TARGET and fail the run.
# Built without a sanitizer (safe Rust; 3-5x more executions), so libFuzzer's malloc limit has no
# hooks: the address space is limited instead (ulimit -v 1.5 GiB), and any allocation over it aborts
# the target, which libFuzzer reports as a crash. -rss_limit_mb catches memory actually touched.
set -e
cd "$(dirname "$0")/.."
RUNS=${RUNS:-1000000}
TARGETS=${*:-"cdr_decode tf_decode text_readers bag_reader mcap_source manifest_preset merge_results"}
for t in $TARGETS; do
    mkdir -p "fuzz/work/$t"
    echo "== $t"
    nice -n 19 cargo +nightly fuzz build -s none -O "$t" 2>/dev/null
    (ulimit -v $((1536 * 1024)); nice -n 19 cargo +nightly fuzz run -s none -O "$t" "fuzz/work/$t" "fuzz/corpus/$t" -- \
        -runs="$RUNS" -rss_limit_mb=1024 -malloc_limit_mb=1024 -timeout=10 -print_final_stats=1 \
        2>&1) | grep -E "^Done|stat::number_of_executed_units|stat::peak_rss_mb|stat::new_units_added|ERROR|panicked|SUMMARY"
done
