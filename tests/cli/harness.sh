# The command-line test scripts' shared part (sourced): a scratch folder $tmp, removed at exit, and the checks'
# "ok" and "FAIL" lines, counted for the summary.
#
#   source "$(dirname "$0")/harness.sh" occtrack_cli
#   pass "what held"; fail "what did not" "detail line" ...; finish   # finish: exit status 1 if any failed
tmp=$(mktemp -d "${TMPDIR:-/tmp}/$1.XXXXXX") || { echo "error: mktemp failed" >&2; exit 2; }
trap 'rm -rf -- "$tmp"' EXIT

passed=0
failed=0
pass() { passed=$((passed + 1)); echo "ok   - $1"; }
fail() {
  failed=$((failed + 1))
  echo "FAIL - $1"
  shift
  local detail
  for detail in "$@"; do printf '       %s\n' "$detail"; done
}
finish() {
  echo "$passed passed, $failed failed"
  [ "$failed" -eq 0 ]
}
