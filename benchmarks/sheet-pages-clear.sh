#!/bin/sh
# Every-sheet scenes as clear as the single-sheet presets (letters 16 voxels high, SNR 8,
# ink contrast 1, blur 0.6 voxel): pairs at 3 to 20 voxels apart (also with ink contrast
# 0.6 and with SNR 4), a roll beside two fragments, books. The table in
# docs/segmentation.md ("Every sheet in the scan"). Usage: sheet-pages-clear.sh [TOOL] [OUTDIR]
T=${1:-build/bin/virtual-unwrap}; O=${2:-/tmp/clear}
C="--param snr=8 --param letter_height=16 --param ink_contrast=1 --param blur=0.6"
run() { /usr/bin/python3 benchmarks/sheet_pages.py run --jobs 2 --tool "$T" "$@" | grep "^| all"; }
i=0; for sep in 3 5 8 12 20; do echo "pair sep $sep"; run --scenes 1 --seed $((5000+i)) --kinds pair --out $O/pair $C --param separation=$sep; i=$((i+1)); done
i=0; for sep in 3 5 8 12 20; do echo "pair ink 0.6 sep $sep"; run --scenes 1 --seed $((5000+i)) --kinds pair --out $O/pairink $C --param ink_contrast=0.6 --param separation=$sep; i=$((i+1)); done
i=0; for sep in 3 5 8 12 20; do echo "pair snr 4 sep $sep"; run --scenes 1 --seed $((5000+i)) --kinds pair --out $O/pairsnr $C --param snr=4 --param separation=$sep; i=$((i+1)); done
echo fragments; run --scenes 6 --seed 7101 --kinds fragments --out $O/fragments $C
echo books; run --scenes 6 --seed 7001 --kinds book --out $O/book $C
