#!/usr/bin/env bash
# The three steps in order, each waiting for the one before: N_th once, the Indexed Job of
# tiles, the merge. The frames end up on the quadray-work volume (OUT in settings.yaml).
set -euo pipefail
cd "$(dirname "$0")"
kubectl apply -f settings.yaml
for job in nth tiles merge; do
  kubectl apply -f "$job-job.yaml"
  kubectl wait --for=condition=complete --timeout=24h "job/quadray-$job"
done
