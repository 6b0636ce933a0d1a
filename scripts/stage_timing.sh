# Sourced by the test scripts. `timed_stage NAME COMMAND...` runs COMMAND and, when STAGE_TIMES names a file
# (scripts/run_tests.sh sets it), appends "NAME<TAB>SECONDS<TAB>EXIT STATUS" to it; the exit status is
# COMMAND's. scripts/check_stage_times.py then prints the table and checks that the stages add up.
timed_stage() {
  local name=$1
  shift
  local start status=0
  start=$(date +%s.%N)
  "$@" || status=$?
  if [ -n "${STAGE_TIMES:-}" ]; then
    printf '%s\t%.1f\t%d\n' "$name" "$(echo "$(date +%s.%N) - $start" | bc)" "$status" >>"$STAGE_TIMES"
  fi
  return "$status"
}
