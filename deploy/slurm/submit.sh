#!/usr/bin/env bash
# Submits a sketchdrape batch to Slurm: an array of SHARDS tasks (one shard each) and a collect
# job that runs after all of them. Prints the two job ids on the last line.
#
#   deploy/slurm/submit.sh [-n SHARDS] [-c CPUS_PER_SHARD] MANIFEST OUT [batch options...]
#
# e.g. SKETCHDRAPE=$PWD/build/sketchdrape deploy/slurm/submit.sh -n 8 wardrobe.json /shared/out
# Options after OUT go to every shard (--stage mesh, --timeout 600, --force, ...). Slurm logs
# go to OUT/slurm/.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
shards=4
cpus=1
while getopts "n:c:" opt; do
  case $opt in
    n) shards=$OPTARG ;;
    c) cpus=$OPTARG ;;
    *) echo "usage: $0 [-n SHARDS] [-c CPUS_PER_SHARD] MANIFEST OUT [batch options...]" >&2; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
if [ $# -lt 2 ]; then
  echo "usage: $0 [-n SHARDS] [-c CPUS_PER_SHARD] MANIFEST OUT [batch options...]" >&2
  exit 2
fi
manifest=$(realpath "$1")
out=$(realpath -m "$2")
shift 2
mkdir -p "$out/slurm"

array=$(sbatch --parsable --array="1-$shards" --cpus-per-task="$cpus" \
  --output="$out/slurm/shard-%a.out" "$here/batch.sbatch" "$manifest" "$out" "$@")
array=${array%%;*}  # "id;cluster" on multi-cluster set-ups
collect=$(sbatch --parsable --dependency="afterany:$array" --output="$out/slurm/collect.out" \
  "$here/collect.sbatch" "$out")
collect=${collect%%;*}
echo "submitted: array job $array ($shards shards), collect job $collect"
echo "$array $collect"
