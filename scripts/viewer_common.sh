# Shared prologue of the scripts that drive pcl_movers_viewer (bench_viewer.sh, make_screenshots.sh).
# Source it after `set -euo pipefail`; the caller's usage text is its leading comment block.
# Defines: root, build, shared, apps, work (a temporary folder removed on exit), sample (the
# simulated sample sequence: data/sample if present, else simulated into $work) and run_viewer.
if [[ $# -lt 1 || "$1" == "-h" || "$1" == "--help" ]]; then
  awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"
  exit $([[ $# -lt 1 ]] && echo 1 || echo 0)
fi
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "$1" 2>/dev/null && pwd)" || { echo "error: build folder $1 not found" >&2; exit 1; }
shared="${2:-$root/../shared/data}"
apps="$build/apps"
for tool in pcl_movers_viewer pcl_movers_detect pcl_movers_simulate; do
  [[ -x "$apps/$tool" ]] || { echo "error: $apps/$tool not built" >&2; exit 1; }
done
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# Off-screen rendering still needs an X server (Debian's VTK is built for X11).
xvfb=()
[[ -n "${DISPLAY:-}" ]] || xvfb=(xvfb-run -a -s "-screen 0 1920x1080x24")
run_viewer() { "${xvfb[@]}" "$apps/pcl_movers_viewer" "$@"; }

sample="$root/data/sample"
if [[ ! -d "$sample" ]]; then
  echo "data/sample not found: simulating data/scenarios/sample.yaml" >&2
  "$apps/pcl_movers_simulate" "$root/data/scenarios/sample.yaml" "$work/sample" >/dev/null
  sample="$work/sample"
fi
