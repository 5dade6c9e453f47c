#!/usr/bin/env bash
# readme_commands_run_as_written: runs every `cargo run` and `shadecache`
# command of the README's ```sh blocks, as written, from the repository
# root, one after the other; a command that fails fails the script, with
# its output. A command continued over lines with `\` is one command.
# `shadecache ...` runs the release build's binary (what `cargo install`
# would put on the PATH). Lines that set a shell variable (`src=...`)
# are run before the commands after them in the same block.
#
#   scripts/readme-commands.sh [FILE.md ...]     # README.md by default
set -euo pipefail
cd "$(dirname "$0")/.."

files=("$@")
if [ ${#files[@]} -eq 0 ]; then files=(README.md); fi

bin_dir=$(mktemp -d)
trap 'rm -rf "$bin_dir"' EXIT
ran=0
failed=0
for file in "${files[@]}"; do
  # One command a line: the sh blocks' lines, continuations joined.
  mapfile -t commands < <(awk '
    /^[[:space:]]*```sh[[:space:]]*$/ { inblock = 1; next }
    /^[[:space:]]*```/ { inblock = 0; next }
    inblock {
      line = $0
      sub(/^[[:space:]]+/, "", line)
      if (pending != "") { line = pending " " line; pending = "" }
      if (line ~ /\\$/) { sub(/\\$/, "", line); pending = line; next }
      print line
    }' "$file")
  prelude=""
  for command in "${commands[@]}"; do
    if [[ "$command" =~ ^[A-Za-z_][A-Za-z0-9_]*= ]]; then
      prelude+="$command; "
      continue
    fi
    case "$command" in
      cargo\ run*|shadecache\ *) ;;
      *) continue ;;
    esac
    if [[ "$command" == shadecache\ * ]] && [ ! -x "$bin_dir/shadecache" ]; then
      cargo build --release --locked --quiet -p shadecache-cli
      ln -s "$PWD/target/release/shadecache" "$bin_dir/shadecache"
    fi
    echo "== $file: $command" >&2
    start=$(date +%s)
    log=$(mktemp)
    if PATH="$bin_dir:$PATH" bash -c "set -euo pipefail; $prelude$command" > "$log" 2>&1; then
      echo "   ok in $(( $(date +%s) - start )) s" >&2
    else
      status=$?
      echo "   FAILED (exit $status) in $(( $(date +%s) - start )) s:" >&2
      tail -40 "$log" >&2
      failed=$((failed + 1))
    fi
    rm -f "$log"
    ran=$((ran + 1))
  done
done
if [ "$ran" -eq 0 ]; then
  echo "readme_commands_run_as_written: no command found in ${files[*]}" >&2
  exit 1
fi
echo "readme_commands_run_as_written: $((ran - failed)) passed, $failed failed" >&2
[ "$failed" -eq 0 ]
