#!/usr/bin/env bash
# A tiled, multi-frame `quadray raytrace` on Kubernetes, the same settings as deploy/slurm/submit.sh:
#   RENDER="--scene /assets/scenes/shadows-bunny.toml --size 1920x1080 --orbit 10 --frames 0..36" \
#   TILES=8 OUT=/work/frames/bunny.png IMAGE=registry.example.com/quadray:0.1.0 CPUS=4 \
#   deploy/kubernetes/run.sh [--print | --resume]
# RENDER: the `quadray raytrace` options without --nth, --tiles or --out (scenes of the image lie
# under /assets/scenes). TILES: bands per frame (8). OUT: the merged picture on the shared volume
# (/work/frames/render.png), one per frame. IMAGE: built from deploy/Dockerfile (see
# docs/deploy.md). CPUS: each work item's CPU request and render threads (1).
# Steps, each waiting for the one before: the volume and the settings (a ConfigMap), N_th once
# (nth-job.yaml), the Indexed Job of items (tiles-job.yaml), the merge (merge-job.yaml).
# --print: the manifests with the settings filled in, applying nothing (no cluster needed).
# --resume: after a failed run, only the items whose tiles are missing (missing-job.yaml finds
# them), with the settings and N_th already on the volume, then the merge.
set -euo pipefail
cd "$(dirname "$0")"
: "${RENDER:?the quadray raytrace options (scene, size, spp, --orbit and --frames A..B)}"
: "${TILES:=8}" "${OUT:=/work/frames/render.png}" "${CPUS:=1}"
: "${IMAGE:?the quadray image, e.g. registry.example.com/quadray:0.1.0 (docs/deploy.md)}"
mode="${1:-}"
frames=1
if [[ " $RENDER " =~ [[:space:]]--frames[[:space:]=]+([0-9]+)\.\.([0-9]+)[[:space:]] ]]; then
  frames=$((BASH_REMATCH[2] - BASH_REMATCH[1]))
fi

quoted() { # $1 as a YAML double-quoted string
  local s=${1//\\/\\\\}
  printf '"%s"' "${s//\"/\\\"}"
}

settings() {
  cat <<EOF
apiVersion: v1
kind: ConfigMap
metadata:
  name: quadray-settings
data:
  RENDER: $(quoted "$RENDER")
  TILES: $(quoted "$TILES")
  OUT: $(quoted "$OUT")
---
EOF
  cat volume.yaml
}

# The manifest of step $1 with the image, and for the items their count, ITEMS and CPUs.
job() {
  local count=${2:-$((frames * TILES))} items=${3:-}
  sed -e "s|image: registry.example.com/quadray:0.1.0 # run.sh: IMAGE|image: $IMAGE|" \
    -e "s|completions: 72 # run.sh:.*|completions: $count|" \
    -e "s|value: \"\" # run.sh: the missing items.*|value: $(quoted "$items")|" \
    -e "s|cpu: \"1\", memory: 2Gi } # run.sh: CPUS|cpu: $(quoted "$CPUS"), memory: 2Gi }|" \
    "$1-job.yaml"
}

# Waits for job quadray-$1 to complete; fails, naming its failed indexes, if it failed.
wait_job() {
  local state
  while :; do
    state=$(kubectl get job "quadray-$1" -o jsonpath='{.status.conditions[?(@.status=="True")].type}')
    case " $state " in
    *" Complete "*) return 0 ;;
    *" Failed "*)
      echo "run: job quadray-$1 failed (failed indexes: $(kubectl get job "quadray-$1" \
        -o jsonpath='{.status.failedIndexes}')); after a fix: $0 --resume" >&2
      return 1
      ;;
    esac
    sleep 10
  done
}

run() { # applies step $1 (with job's other arguments) and waits for it
  kubectl delete job "quadray-$1" --ignore-not-found
  job "$@" | kubectl apply -f -
  wait_job "$1"
}

case "$mode" in
--print)
  settings
  for step in nth tiles merge missing; do
    echo ---
    job "$step"
  done
  ;;
--resume)
  settings | kubectl apply -f -
  kubectl delete job quadray-merge --ignore-not-found
  run missing
  # Its log holds the indices (stdout) and what they are (stderr): the indices alone.
  missing=$(kubectl logs job/quadray-missing | grep -E '^([0-9]+|all)$' | paste -sd ' ' || true)
  if [[ "$missing" == all ]]; then
    run tiles
  elif [[ -n "$missing" ]]; then
    echo "run: re-running items $missing"
    run tiles "$(wc -w <<<"$missing")" "$missing"
  fi
  run merge
  ;;
"")
  settings | kubectl apply -f -
  run nth
  run tiles
  run merge
  ;;
*)
  echo "usage: $0 [--print | --resume]" >&2
  exit 2
  ;;
esac
