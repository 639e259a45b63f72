#!/usr/bin/env bash
# A tiled, multi-frame `quadray raytrace` on Slurm: N_th computed once, a job array of work items
# (Slurm sets SLURM_ARRAY_TASK_ID, quadray reads it: item = (frame - A) * TILES + tile), and a
# merge job that starts when every item succeeded (afterok). Run from a shared folder:
#   RENDER="--scene scenes/shadows-bunny.toml --size 1920x1080 --orbit 10 --frames 0..36" \
#   FRAMES=36 TILES=8 OUT=frames/bunny.png deploy/slurm/submit.sh
set -euo pipefail
here="$(dirname "$0")"
: "${RENDER:?the quadray raytrace options (scene, size, spp, --orbit and --frames)}"
: "${FRAMES:=1}" "${TILES:=8}" "${OUT:=frames/render.png}" "${WORK:=quadray-tiles}"
export RENDER TILES OUT WORK
mkdir -p "$WORK" logs
# One N_th for all tiles, computed here once (a short calibration and pilot render).
NTH=$(quadray raytrace $RENDER --print-nth)
export NTH
array=$(sbatch --parsable --array=0-$((FRAMES * TILES - 1)) "$here/tile.sbatch")
sbatch --dependency=afterok:"$array" "$here/merge.sbatch"
