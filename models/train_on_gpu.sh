#!/bin/bash
# Two fine-tunes of the shipped float network side by side on one GPU,
# each with its own processes making batches: the command a session lent a
# GPU machine runs there (models/README.md, "Training on a GPU"). It reads
# the pack that models/pack_training_data.py writes to target/gpu-pack and
# writes each run's models, checkpoint and log to $OUT/a and $OUT/b.
#
# LIMIT: seconds of training for each run (the script fits its schedule
# to them). LR_A, SEED_A, LR_B, SEED_B: each run's learning rate and seed;
# run a takes the mix of r1 and r2, run b r3's (models/history.md, "The
# network shipped now"). PY, DEVICE, WORKERS, BATCH, STEPS, EVERY: to try
# the command on a CPU first, e.g.
#   OUT=/tmp/o PY=.venv-train/bin/python DEVICE=cpu WORKERS=2 BATCH=16 STEPS=30 EVERY=10 \
#       models/train_on_gpu.sh
set -u
pack=target/gpu-pack
py=${PY:-python3}
nvidia-smi --query-gpu=name,memory.total --format=csv 2>&1 | head -2
"$py" -c "import torch, onnx, onnxruntime, cv2, numpy; print('torch', torch.__version__, 'onnx', onnx.__version__,
    'onnxruntime', onnxruntime.__version__, 'cv2', cv2.__version__, 'numpy', numpy.__version__,
    'cuda', torch.cuda.is_available())"
# The workers hand their batches over in shared memory: 4 batches ahead
# each, about 26 MB a batch of 64.
if [ "$(df --output=avail -k /dev/shm | tail -1)" -lt 4000000 ]; then
    mount -o remount,size=16G /dev/shm
fi
df -h /dev/shm | tail -1
common=(--device "${DEVICE:-cuda}" --workers "${WORKERS:-7}" --batch "${BATCH:-64}"
    --steps "${STEPS:-20000}" --time-limit-s "${LIMIT:-390}" --checkpoint-every "${EVERY:-1000}"
    --data $pack/cables-dev --synthetic $pack/render-train $pack/render-workbench $pack/render-dark2
    --busy $pack/render-busy4 $pack/render-busy5 $pack/render-ptrain $pack/render-ptrain2
    --init models/cable_segmentation_float.onnx --paste-fraction 0.5)
# One run in the background: NAME LR REAL_FRACTION BUSY_FRACTION SEED.
run() {
    mkdir -p "$OUT/$1"
    PYTHONUNBUFFERED=1 "$py" models/train_segmentation.py "${common[@]}" --lr "$2" \
        --real-fraction "$3" --busy-fraction "$4" --seed "$5" \
        --out "$OUT/$1/cable_segmentation.onnx" >"$OUT/$1/train.log" 2>&1 &
}
run a "${LR_A:-3e-4}" 0.3 0.45 "${SEED_A:-80}"
run b "${LR_B:-2e-4}" 0.25 0.55 "${SEED_B:-81}"
wait -n; first=$?
wait -n; second=$?
grep -h "steps fit\|training took\|exported\|threshold 0.5\|Error" "$OUT/a/train.log" "$OUT/b/train.log"
[ "$first" -eq 0 ] && [ "$second" -eq 0 ]
