#!/bin/sh
# rtu-soc-vp --data PREFIX with PREFIX.rtubvh garbled (the real rays and hits beside it): exit 2
# with a message naming the image, not SystemC's uncaught-exception error (exit 1).
# Usage: soc_vp_bad_image_test.sh RTU_SOC_VP DATA_PREFIX
set -u
vp=$1 data=$2
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
cp "$data.rays" "$d/x.rays"
cp "$data.hits" "$d/x.hits"
head -c 1536 /dev/zero | tr '\0' 'x' >"$d/x.rtubvh"
"$vp" --data "$d/x" 2>"$d/err" >/dev/null
status=$?
cat "$d/err"
[ "$status" = 2 ] || { echo "FAIL: exit $status, not 2"; exit 1; }
grep -q "x.rtubvh: " "$d/err" || { echo "FAIL: the message does not name the image"; exit 1; }
echo "ok: exit 2 naming the image"
