# libFuzzer targets of test/fuzz/ (standalone CMake project, clang): build,
# corpus regression, timed fuzzing, JUnit result. Source after common.sh;
# used by fuzz.sh and test.sh.
#
# Layout under .build/fuzz/: build tree (fuzz_config, fuzz_csv, fuzz_ingest,
# fuzz_bag), work/<target>/ (units the fuzzer finds; kept between runs, not
# checked in), artifacts/<target>/ (crash-*, leak-*, timeout-*, oom-*),
# logs/<target>.{regress,fuzz}.log, tmp/ (fuzz_bag's temporary bag files).

PC_EKF_FUZZ_TARGETS=(config csv ingest bag)
PC_EKF_FUZZ_DIR=$PC_EKF_ROOT/.build/fuzz
PC_EKF_FUZZ_SRC=$PC_EKF_ROOT/test/fuzz

# Per-input limits (libFuzzer flags). A config, a CSV or a 48-sample ingest
# input needs far less than 256 MB; a larger single allocation is a bug
# (e.g. parsing allocating by `sampling.samples`). 25 s per input: the slowest
# seeds take < 1 s under ASan on a loaded 2-core machine.
pc_ekf_fuzz_flags() {
  local target=$1 dict=$PC_EKF_FUZZ_SRC/$1.dict
  echo "-timeout=25 -rss_limit_mb=2048 -malloc_limit_mb=256 -print_final_stats=1"
  [ -f "$dict" ] && echo "-dict=$dict"
}

# Sanitizer runtime options: abort on the first report, full stack traces,
# leaks checked (libFuzzer checks each new unit too).
pc_ekf_fuzz_env() {
  export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1:symbolize=1:allocator_may_return_null=0${PC_EKF_FUZZ_ASAN_EXTRA:+:$PC_EKF_FUZZ_ASAN_EXTRA}"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  local symbolizer
  symbolizer=$(command -v llvm-symbolizer || command -v llvm-symbolizer-14 || true)
  [ -n "$symbolizer" ] && export ASAN_SYMBOLIZER_PATH=$symbolizer
  mkdir -p "$PC_EKF_FUZZ_DIR/tmp"
  export TMPDIR=$PC_EKF_FUZZ_DIR/tmp
}

# Builds the targets (clang, -j${PC_EKF_FUZZ_JOBS:-2}). fuzz_bag needs the
# generated message headers: when the workspace has none yet, only the
# message target of the catkin workspace is built.
pc_ekf_fuzz_build() {
  local msg_include=$PC_EKF_WS/devel/include
  if [ ! -f "$msg_include/pc_ekf/RoadProfile.h" ]; then
    pc_ekf_log "fuzz: generating the message headers (catkin_make pc_ekf_generate_messages_cpp)"
    pc_ekf_catkin_make pc_ekf_generate_messages_cpp >"$PC_EKF_ROOT/.build/fuzz_msgs.log" 2>&1 || {
      tail -20 "$PC_EKF_ROOT/.build/fuzz_msgs.log" >&2
      return 1
    }
  fi
  mkdir -p "$PC_EKF_FUZZ_DIR/logs"
  CC=clang CXX=clang++ cmake -S "$PC_EKF_FUZZ_SRC" -B "$PC_EKF_FUZZ_DIR" \
    -DCMAKE_BUILD_TYPE=Fuzz -DPC_EKF_MSG_INCLUDE_DIR="$msg_include" \
    >"$PC_EKF_FUZZ_DIR/logs/configure.log" 2>&1 || {
    tail -20 "$PC_EKF_FUZZ_DIR/logs/configure.log" >&2
    return 1
  }
  cmake --build "$PC_EKF_FUZZ_DIR" -j"${PC_EKF_FUZZ_JOBS:-2}" \
    >"$PC_EKF_FUZZ_DIR/logs/build.log" 2>&1 || {
    grep -E "error|Error" "$PC_EKF_FUZZ_DIR/logs/build.log" | head -20 >&2
    return 1
  }
}

# Copies the target's new crash/leak/timeout/oom inputs into its corpus (so
# the regression run keeps replaying them) and lists them; 1 when any.
pc_ekf_fuzz_collect_artifacts() {
  local target=$1 found=0 f
  for f in "$PC_EKF_FUZZ_DIR/artifacts/$target"/*; do
    [ -f "$f" ] || continue
    cp "$f" "$PC_EKF_FUZZ_SRC/corpus/$target/"
    echo "$target: $(basename "$f") -> test/fuzz/corpus/$target/$(basename "$f")"
    rm -f "$f"
    found=1
  done
  return $found
}

# Runs every input of test/fuzz/corpus/<target> once (seeds and every
# crash input found so far). 0 when none fails.
pc_ekf_fuzz_regress() {
  local target=$1 log=$PC_EKF_FUZZ_DIR/logs/$1.regress.log
  mkdir -p "$PC_EKF_FUZZ_DIR/artifacts/$target"
  # shellcheck disable=SC2046
  (cd "$PC_EKF_FUZZ_DIR" && "./fuzz_$target" $(pc_ekf_fuzz_flags "$target") -runs=0 \
     -artifact_prefix="$PC_EKF_FUZZ_DIR/artifacts/$target/" "$PC_EKF_FUZZ_SRC/corpus/$target") \
    >"$log" 2>&1
}

# Fuzzes <target> for <seconds> starting from the work corpus and the seeds
# (new units go to .build/fuzz/work/<target>). 0 when nothing was found.
pc_ekf_fuzz_run() {
  local target=$1 seconds=$2 log=$PC_EKF_FUZZ_DIR/logs/$1.fuzz.log
  mkdir -p "$PC_EKF_FUZZ_DIR/work/$target" "$PC_EKF_FUZZ_DIR/artifacts/$target"
  # shellcheck disable=SC2046
  (cd "$PC_EKF_FUZZ_DIR" && "./fuzz_$target" $(pc_ekf_fuzz_flags "$target") \
     -max_total_time="$seconds" -artifact_prefix="$PC_EKF_FUZZ_DIR/artifacts/$target/" \
     "$PC_EKF_FUZZ_DIR/work/$target" "$PC_EKF_FUZZ_SRC/corpus/$target") >"$log" 2>&1
}

# "execs N, corpus N units / N bytes, coverage N" from a fuzz log.
pc_ekf_fuzz_summary() {
  local log=$1 execs corp cov
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  corp=$(grep -oE 'corp: [0-9]+/[0-9]+[a-zA-Z]*' "$log" | tail -1 | sed 's/corp: //')
  cov=$(grep -oE 'cov: [0-9]+' "$log" | tail -1 | sed 's/cov: //')
  echo "execs ${execs:-?}, corpus ${corp:-?} (units/bytes), coverage ${cov:-?} edges"
}

# The sanitizer/libFuzzer report of a failed run, for messages.
pc_ekf_fuzz_report() {
  grep -E "ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer)|runtime error:|SUMMARY:|==[0-9]+== ERROR|Test unit written|ALARM|out-of-memory|deadly signal|terminate called|what\(\)" "$1" |
    head -8
}

# test.sh's fuzz step: builds the targets, then per target replays the
# corpus and fuzzes for SECONDS (PC_EKF_FUZZ_PARALLEL targets at a time,
# default 2), and writes RESULTS_DIR/fuzz.xml: one JUnit test case per target
# (fuzz.<target>), failed on a build failure, a regression failure or a
# finding; a finding's input is copied into test/fuzz/corpus/<target>/.
pc_ekf_fuzz_ci() {
  local results=$1 seconds=$2 parallel=${PC_EKF_FUZZ_PARALLEL:-2} status_dir target
  status_dir=$PC_EKF_FUZZ_DIR/status
  rm -rf "$status_dir"
  mkdir -p "$status_dir" "$results"
  if ! pc_ekf_fuzz_build; then
    for target in "${PC_EKF_FUZZ_TARGETS[@]}"; do
      printf 'FAILED\nbuild failed (.build/fuzz/logs/build.log)\n' >"$status_dir/$target"
    done
  else
    pc_ekf_fuzz_env
    local pids=() pid
    for target in "${PC_EKF_FUZZ_TARGETS[@]}"; do
      pc_ekf_fuzz_ci_target "$target" "$seconds" >"$status_dir/$target" 2>&1 &
      pids+=("$!")
      if [ ${#pids[@]} -ge "$parallel" ]; then
        wait "${pids[0]}"
        pids=("${pids[@]:1}")
      fi
    done
    for pid in "${pids[@]}"; do wait "$pid"; done
  fi
  PYTHONPATH=$PC_EKF_JUNIT_PATH /usr/bin/python3 - "$results/fuzz.xml" "$status_dir" \
    "${PC_EKF_FUZZ_TARGETS[@]}" <<'PY'
import os, sys
import junit
out, status_dir, targets = sys.argv[1], sys.argv[2], sys.argv[3:]
cases = []
for t in targets:
    path = os.path.join(status_dir, t)
    lines = open(path).read().splitlines() if os.path.exists(path) else ["FAILED", "no result"]
    text = "\n".join(lines[1:])
    failed = not lines or lines[0] != "ok"
    cases.append(junit.Case(t, failure="fuzz_%s failed" % t if failed else None,
                            failure_text=text, system_out=text))
junit.write(out, "fuzz", cases)
PY
}

# One target of pc_ekf_fuzz_ci; prints "ok" or "FAILED", then details.
pc_ekf_fuzz_ci_target() {
  local target=$1 seconds=$2 start=$SECONDS logs=$PC_EKF_FUZZ_DIR/logs
  if ! pc_ekf_fuzz_regress "$target"; then
    echo FAILED
    echo "corpus regression failed (.build/fuzz/logs/$target.regress.log):"
    pc_ekf_fuzz_report "$logs/$target.regress.log"
    pc_ekf_fuzz_collect_artifacts "$target"
    return
  fi
  local ok=1
  pc_ekf_fuzz_run "$target" "$seconds" || ok=0
  local found
  found=$(pc_ekf_fuzz_collect_artifacts "$target") || ok=0
  if [ $ok -eq 1 ]; then echo ok; else echo FAILED; pc_ekf_fuzz_report "$logs/$target.fuzz.log"; fi
  [ -n "$found" ] && echo "$found"
  echo "corpus ($(ls "$PC_EKF_FUZZ_SRC/corpus/$target" | wc -l) files) replayed; fuzzed ${seconds} s:" \
    "$(pc_ekf_fuzz_summary "$logs/$target.fuzz.log"); $((SECONDS - start)) s in all"
}
