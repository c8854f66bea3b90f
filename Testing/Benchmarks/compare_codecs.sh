#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Adaptive-FAM against ZFP at the same RMSE on every raw volume of a folder (`afam compare-codecs`),
# printed as a markdown table: per volume and relative RMSE bound, Adaptive-FAM's ratio (raw file
# bytes / .afam bytes, all levels stored), RMSE and max error on the finest level, encode time,
# next to ZFP fixed-accuracy tuned to an RMSE at or below the one Adaptive-FAM reached.
#
# usage: Testing/Benchmarks/compare_codecs.sh [AFAM_EXE] [OUT_CSV] [-- extra compare-codecs options]
#   AFAM_EXE  default build/Apps/afam;  OUT_CSV default /tmp/afam_compare_codecs.csv
# Env: DATA (folder of name_XxYxZ_type.raw volumes; default Testing/Data/volumes, the corpus), BOUNDS (default "1e-2 1e-3"), THREADS (default 2).
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
AFAM="$here/build/Apps/afam"
CSV=/tmp/afam_compare_codecs.csv
[[ $# -gt 0 && $1 != -- ]] && { AFAM="$1"; shift; }
[[ $# -gt 0 && $1 != -- ]] && { CSV="$1"; shift; }
[[ $# -gt 0 && $1 == -- ]] && shift
if [[ -z ${DATA:-} ]]; then
  DATA="$here/Testing/Data/volumes"
fi
BOUNDS="${BOUNDS:-1e-2 1e-3}"
THREADS="${THREADS:-2}"
[[ -x $AFAM ]] || { echo "compare_codecs.sh: no afam executable at $AFAM (build it or pass its path)" >&2; exit 1; }
shopt -s nullglob
volumes=("$DATA"/*.raw)
[[ ${#volumes[@]} -gt 0 ]] || { echo "compare_codecs.sh: no .raw volume in $DATA" >&2; exit 1; }

cmd=("$AFAM" compare-codecs "${volumes[@]}" --bounds "${BOUNDS// /,}" --threads "$THREADS" --csv "$CSV" "$@")
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "command: afam compare-codecs DATA/*.raw --bounds ${BOUNDS// /,} --threads $THREADS --csv $CSV $*  (DATA=$DATA)"
"${cmd[@]}" > /dev/null
echo
echo "| volume | bound | Adaptive-FAM ratio | RMSE (/range) | max error | encode s | ZFP ratio | ZFP RMSE (/range) | ZFP max error | ZFP s | ZFP tolerance | Adaptive-FAM / ZFP ratio |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
# The CSV alternates an adaptive-fam row and the zfp row tuned to it.
awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next }
  $c["codec"] == "adaptive-fam" { split($0, a, ","); next }
  $c["codec"] == "zfp" {
    tol = $c["setting"]; sub(/.*tolerance=/, "", tol); sub(/=.*/, "", tol)
    ra = a[c["ratio"]]; rz = $c["ratio"]
    printf "| %s | %s | %.3g | %.3g (%.2g) | %.3g | %.3f | %.3g | %.3g (%.2g) | %.3g | %.4f | %s | %.3g |\n",
      $c["volume"], $c["bound"], ra, a[c["rmse"]], a[c["rmse_relative"]], a[c["max_error"]], a[c["seconds"]],
      rz, $c["rmse"], $c["rmse_relative"], $c["max_error"], $c["seconds"], tol, ra / rz
    if (!($c["bound"] in n)) order[++nb] = $c["bound"]
    n[$c["bound"]]++; if (ra + 0 >= rz + 0) win[$c["bound"]]++; if (ra + 0 > 1) above1[$c["bound"]]++
  }
  END {
    print ""
    for (k = 1; k <= nb; ++k) { b = order[k]
      printf "bound %s: Adaptive-FAM ratio >= ZFP on %d of %d volumes, above 1 on %d of %d\n",
        b, win[b] + 0, n[b], above1[b] + 0, n[b] }
  }' "$CSV"
