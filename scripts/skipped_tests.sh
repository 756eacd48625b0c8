#!/usr/bin/env bash
# Prints one block saying how many tests skipped and why, from the JUnit file `ctest --output-junit`
# wrote: each distinct reason (the message after GoogleTest's "Skipped" line) with the tests it skipped.
#   scripts/skipped_tests.sh build/ctest-junit.xml
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: scripts/skipped_tests.sh JUNIT_XML" >&2; exit 2; }
[ -f "$1" ] || { echo "[test] no test results at $1: skipped tests unknown"; exit 0; }
awk '
  function unescape(s) {
    gsub(/&lt;/, "<", s); gsub(/&gt;/, ">", s); gsub(/&quot;/, "\"", s); gsub(/&apos;/, "\047", s)
    gsub(/&amp;/, "\\&", s)
    return s
  }
  /<testcase / {
    total++
    name = $0; sub(/.*<testcase name="/, "", name); sub(/".*/, "", name)
    skipped = $0 ~ /status="notrun"/
    reading = 0; why = ""
  }
  /<\/testcase>/ {
    if (skipped) {
      count++
      if (why == "") why = "no reason given"
      if (!(why in tests)) order[++reasons] = why
      tests[why] = tests[why] (tests[why] == "" ? "" : ", ") unescape(name)
    }
    skipped = 0; reading = 0
  }
  skipped && reading && (/^\[  SKIPPED \]/ || /^[ \t]*$/) { reading = 0 }
  skipped && reading { line = $0; gsub(/^[ \t]+|[ \t]+$/, "", line); why = why (why == "" ? "" : " ") unescape(line) }
  skipped && /: Skipped$/ { reading = 1 }
  END {
    if (count == 0) { printf "[test] no test skipped (%d tests)\n", total; exit }
    printf "[test] %d of %d tests skipped:\n", count, total
    for (i = 1; i <= reasons; i++) printf "[test]   %s: %s\n", order[i], tests[order[i]]
  }
' "$1"
