#!/bin/sh
# The walk-through of docs/calibration.md ("Walk-through on the sample set"), run in a copy of
# this folder with tactile_calibrate and tactile_extract on PATH. A test runs exactly this.
set -e
REFS="--reference reference-0.pgm --reference reference-1.pgm --reference reference-2.pgm --reference reference-3.pgm"
# 1. Where the elements are: a light press against the no-load references.
tactile_calibrate layout press.pgm $REFS --sensor-id left --mm-per-px 0.025 --radius 14 \
    --rings 1,8,16,16 --ring-polar-deg 0,10,20,30 -o layout.yaml --marks marks.pgm
# 2. What each element measures under the known loads of loads.csv.
tactile_calibrate measure --calibration layout.yaml $REFS --loads loads.csv -o samples.csv
# 3. The curves, fitted to the samples: the calibration.
tactile_calibrate fit --calibration layout.yaml --samples samples.csv --shear-knots 2 -o left.yaml
# 4. Check: measure a loaded frame with it; compare with loads.csv's rows for loaded/f04.pgm.
tactile_extract --calibration left.yaml $REFS --format table loaded/f04.pgm
