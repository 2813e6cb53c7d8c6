# shellcheck shell=bash
# The rule by which SPECULA_ALLOW_SKIP names a requirement, for the scripts: the same as the
# testkit's `allowed` (crates/specula-testkit/src/lib.rs), which its tests hold this file to:
# comma-separated words, each trimmed of white space, compared ignoring ASCII case.
#   source scripts/allow-skip.sh; specula_allowed gpu && echo "gpu may be skipped"
specula_allowed() {
  local want word words
  want="$(printf '%s' "$1" | tr '[:upper:]' '[:lower:]')"
  IFS=',' read -r -a words <<< "${SPECULA_ALLOW_SKIP:-}"
  for word in "${words[@]}"; do
    word="${word#"${word%%[![:space:]]*}"}"
    word="${word%"${word##*[![:space:]]}"}"
    [[ "$(printf '%s' "$word" | tr '[:upper:]' '[:lower:]')" == "$want" ]] && return 0
  done
  return 1
}
