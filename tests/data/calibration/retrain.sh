#!/bin/sh
# "Retraining for your own sensor" (docs/calibration.md, docs/slip.md): after walkthrough.sh has
# fitted left.yaml, the rig renders that sensor in a small sweep and slip_train trains a slip model
# on runs of it. Run in the same folder with rig and slip_train on PATH. A test runs exactly this;
# a real retraining takes more scenarios, seeds and trees (docs/slip.md).
set -e
# 5. A sweep on the fitted sensor: every scenario's camera takes the file's image, and its scenario
#    file and report name the file.
rig --sweep 2 --seed 20 --detectors learned --max-sim-time 6 --jobs 2 --calibration left.yaml \
    --out sweep
# 6. A slip model trained on runs of the fitted sensor.
slip_train --calibration left.yaml --seeds 105 --scenarios 2 --max-time 6 --trees 4 --depth 3 \
    --jobs 2 --out slip_model.inc
