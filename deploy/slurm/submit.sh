#!/usr/bin/env bash
# A tiled, multi-frame `quadray raytrace` on Slurm: N_th computed once here, a job array of work
# items (Slurm sets SLURM_ARRAY_TASK_ID, quadray reads it: item = (frame - A) * TILES + tile), and
# a merge job that starts when every item succeeded and is cancelled if one fails. Run it from a
# folder every node sees, with `quadray` on the PATH of the nodes:
#   RENDER="--scene scenes/shadows-bunny.toml --size 1920x1080 --orbit 10 --frames 0..36" \
#   TILES=8 OUT=frames/bunny.png deploy/slurm/submit.sh [SBATCH OPTIONS...]
# RENDER: the `quadray raytrace` options (scene, size, spp, --orbit and --frames A..B), without
# --nth, --tiles or --out. TILES: bands per frame (8). OUT: the merged picture, one per frame
# (frames/render.png). WORK: the tiles' folder (quadray-tiles); its logs/ holds the jobs' logs.
# CPUS: the CPUs of each work item (1, which fits any node; quadray uses as many threads).
# Every other argument goes to both sbatch calls: --partition=P, --time=T, --account=A, ...
# After a failed or cancelled item (the merge job is then cancelled, DependencyNeverSatisfied):
#   deploy/slurm/submit.sh --resume WORK [SBATCH OPTIONS...]
# submits again exactly the items whose tiles are missing (`quadray tiles missing WORK`) with the
# settings and N_th recorded in WORK/submit.env, then the merge.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
if [[ "${1:-}" == "--resume" ]]; then
  WORK="${2:?--resume needs the tiles folder}"
  shift 2
  [[ -f "$WORK/submit.env" ]] || {
    echo "submit: $WORK/submit.env not found: not a folder submit.sh wrote" >&2
    exit 1
  }
  # RENDER TILES OUT CPUS NTH ITEMS, as the first submission recorded them.
  # shellcheck source=/dev/null
  source "$WORK/submit.env"
  if compgen -G "$WORK/*.exr" >/dev/null; then
    array=$(quadray tiles missing "$WORK")
  else
    array="0-$((ITEMS - 1))"
  fi
else
  : "${RENDER:?the quadray raytrace options (scene, size, spp, --orbit and --frames A..B)}"
  : "${TILES:=8}" "${OUT:=frames/render.png}" "${WORK:=quadray-tiles}" "${CPUS:=1}"
  frames=1
  if [[ " $RENDER " =~ [[:space:]]--frames[[:space:]=]+([0-9]+)\.\.([0-9]+)[[:space:]] ]]; then
    frames=$((BASH_REMATCH[2] - BASH_REMATCH[1]))
  fi
  ITEMS=$((frames * TILES))
  mkdir -p "$WORK"
  # One N_th for all tiles, computed here once (a short calibration and pilot render).
  read -ra options <<<"$RENDER"
  NTH=$(quadray raytrace "${options[@]}" --print-nth)
  for name in RENDER TILES OUT CPUS NTH ITEMS; do
    printf '%s=%q\n' "$name" "${!name}"
  done >"$WORK/submit.env"
  array="0-$((ITEMS - 1))"
fi
export RENDER TILES OUT WORK NTH
mkdir -p "$WORK/logs" "$(dirname "$OUT")"
echo "submit: N_th $NTH, $ITEMS items ($TILES tiles a frame), settings in $WORK/submit.env"
dependency=()
if [[ -n "$array" ]]; then
  job=$(sbatch --parsable --array="$array" --cpus-per-task="$CPUS" \
    --output="$WORK/logs/tile-%A_%a.out" "$@" "$here/tile.sbatch")
  job=${job%%;*} # "id;cluster" on a federation
  echo "submit: array job $job, items $array, $CPUS CPUs each, logs $WORK/logs/tile-${job}_I.out"
  dependency=(--dependency=afterok:"$job" --kill-on-invalid-dep=yes)
else
  echo "submit: no item is missing"
fi
merge=$(sbatch --parsable "${dependency[@]}" --output="$WORK/logs/merge-%j.out" "$@" \
  "$here/merge.sbatch")
merge=${merge%%;*}
echo "submit: merge job $merge, frames to $OUT, log $WORK/logs/merge-$merge.out"
