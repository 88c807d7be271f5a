#!/usr/bin/env bash
# Regenerates every shipped campaign in this folder from the simulator.
# Run from the repository root: bash datasets/generate.sh
set -euo pipefail
rk() { cargo run --quiet --release -- "$@"; }
cd "$(dirname "$0")/.."
D=datasets
# COMAU SMART5 NJ 220-2.7, true robot of seed 1 (seeds 003/004 set-up)
rk simulate --robot comau-nj220 --kind lhs --poses 300 --seed 1 -o $D/comau_lhs.csv
rk simulate --robot comau-nj220 --kind verify --poses 30 --seed 1 -o $D/comau_verify.csv
rk simulate --robot comau-nj220 --kind circle --poses 72 --seed 1 -o $D/comau_circle.csv
# the same robot and poses with one undeclared effect each (controls: comau_lhs.csv)
rk simulate --robot comau-nj220 --poses 300 --seed 1 --effect temperature:delta_k=6,tau_s=1200 -o $D/comau_temperature.csv
rk simulate --robot comau-nj220 --poses 300 --seed 1 --effect payload:kg=0/60/120 -o $D/comau_payload.csv
rk simulate --robot comau-nj220 --poses 300 --seed 1 --effect harmonic:joint=2,period_deg=7.5,amp_deg=0.004 -o $D/comau_harmonic.csv
rk simulate --robot comau-nj220 --poses 300 --seed 1 --effect tracker-step:row=150,dx=0.15,dy=-0.1,dz=0.1 -o $D/comau_tracker_step.csv
rk simulate --robot comau-nj220 --poses 300 --seed 1 --effect crosstalk:joint=1,from=2,gain_deg=0.01 -o $D/comau_crosstalk.csv
rk simulate --robot comau-nj220 --poses 300 --seed 1 --effect hysteresis:joint=2,amp_deg=0.01,travel_deg=20 -o $D/comau_hysteresis.csv
# SCARA RH-3FRH5515 indexing tests (seed 000 §2.3)
rk simulate --robot scara-rh3frh5515 --kind indexing --cycles 3 --seed 1 -o $D/scara_indexing.csv
