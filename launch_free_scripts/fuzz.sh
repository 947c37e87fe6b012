#!/usr/bin/env bash
# Fuzzes the input paths with libFuzzer (clang, -fsanitize=fuzzer,address,undefined):
# fuzz_config (YAML config loader), fuzz_csv (measurement/road CSV readers),
# fuzz_ingest (OneStepFilter::process on arbitrary measurements), fuzz_bag
# (readBag on corrupted/truncated bags). Targets: test/fuzz/fuzz_*.cpp,
# seed corpora: test/fuzz/corpus/<target>/.
#
#   launch_free_scripts/fuzz.sh [SECONDS] [TARGET...]
#       SECONDS per target (default 60); TARGET among config csv ingest bag
#       (default all). Each target first replays its corpus, then fuzzes.
#   --merge   afterwards add the units that raise coverage to the checked-in
#             corpus (libFuzzer -merge=1; review before committing)
#
# Exit status non-zero on any crash, leak, timeout, out-of-memory or
# sanitizer report; the offending input is copied into
# test/fuzz/corpus/<target>/ so the regression run (also in test.sh) keeps
# replaying it. Logs: .build/fuzz/logs/.
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/lib/common.sh"
pc_ekf_require_sources fuzz.sh
source "$here/lib/fuzz.sh"

seconds=60
merge=0
targets=()
for arg in "$@"; do
  case "$arg" in
    --merge) merge=1 ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    [0-9]*) seconds=$arg ;;
    config|csv|ingest|bag) targets+=("$arg") ;;
    *) echo "fuzz.sh: unknown argument '$arg' (see --help)" >&2; exit 2 ;;
  esac
done
[ ${#targets[@]} -eq 0 ] && targets=("${PC_EKF_FUZZ_TARGETS[@]}")

pc_ekf_ensure_packages || exit 1
mkdir -p "$PC_EKF_ROOT/.build"
pc_ekf_log "fuzz: building the targets (.build/fuzz)"
pc_ekf_fuzz_build || { pc_ekf_log "fuzz: build failed (.build/fuzz/logs/build.log)"; exit 1; }
pc_ekf_fuzz_env

failed=0
for target in "${targets[@]}"; do
  start=$SECONDS
  if ! pc_ekf_fuzz_regress "$target"; then
    pc_ekf_log "fuzz_$target: corpus regression FAILED (.build/fuzz/logs/$target.regress.log)"
    pc_ekf_fuzz_report "$PC_EKF_FUZZ_DIR/logs/$target.regress.log" >&2
    pc_ekf_fuzz_collect_artifacts "$target" >&2
    failed=1
    continue
  fi
  pc_ekf_log "fuzz_$target: corpus ok; fuzzing ${seconds} s"
  if pc_ekf_fuzz_run "$target" "$seconds"; then
    status=ok
  else
    status=FAILED
    failed=1
    pc_ekf_fuzz_report "$PC_EKF_FUZZ_DIR/logs/$target.fuzz.log" >&2
  fi
  pc_ekf_fuzz_collect_artifacts "$target" >&2 || failed=1
  if [ "$merge" -eq 1 ] && [ "$status" = ok ]; then
    # shellcheck disable=SC2046
    (cd "$PC_EKF_FUZZ_DIR" && "./fuzz_$target" $(pc_ekf_fuzz_flags "$target") -merge=1 \
       "$PC_EKF_FUZZ_SRC/corpus/$target" "$PC_EKF_FUZZ_DIR/work/$target") \
      >"$PC_EKF_FUZZ_DIR/logs/$target.merge.log" 2>&1 &&
      pc_ekf_log "fuzz_$target: merged into test/fuzz/corpus/$target ($(ls "$PC_EKF_FUZZ_SRC/corpus/$target" | wc -l) files)"
  fi
  echo "fuzz_$target: $status in $((SECONDS - start)) s; $(pc_ekf_fuzz_summary "$PC_EKF_FUZZ_DIR/logs/$target.fuzz.log")"
done
exit $failed
