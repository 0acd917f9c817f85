#!/bin/sh
# Issue 49: on the shared memory path, LT's cycles do not depend on the platform's global quantum,
# even with a RAM that waits an initiator's offset out inside b_transport once it reaches the
# quantum (--ram-syncs, as a quantum keeper would). The example platform at three quanta (1 ns,
# 10 ns, 1 us): every check passes and both jobs' cycles are the same at each.
# Usage: soc_vp_quanta_test.sh RTU_SOC_VP
set -eu
vp=$1
first=""
for q in 1 10 1000; do
  status=0
  out=$("$vp" --fidelity lt --memory shared --ram-syncs --quantum "$q" 2>&1) || status=$?
  [ "$status" = 0 ] || { echo "$out"; echo "FAIL: exit $status at quantum $q ns"; exit 1; }
  echo "$out" | grep -q " passed, 0 failed" || { echo "$out"; echo "FAIL: a check failed at quantum $q ns"; exit 1; }
  cycles=$(echo "$out" | grep -E "^(register-mode job|descriptor chain's last job):" | tr '\n' ' ')
  [ -n "$cycles" ] || { echo "$out"; echo "FAIL: no cycles printed at quantum $q ns"; exit 1; }
  echo "quantum $q ns: $cycles"
  if [ -z "$first" ]; then first=$cycles; elif [ "$cycles" != "$first" ]; then echo "FAIL: the cycles depend on the quantum"; exit 1; fi
done
echo "the same cycles at every quantum"
