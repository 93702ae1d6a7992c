"""Run by the LeRobot venv's Python (tests/run/lerobot_venv.py): open ROOT with LeRobot 0.6.1's own
``LeRobotDataset`` and write every frame it gives to OUT (.npz): state, action, indices, timestamps, the decoded
camera frames (uint8, HWC), and the metadata LeRobot read."""

import json
import sys

import numpy as np
from lerobot.datasets.lerobot_dataset import LeRobotDataset

root, out = sys.argv[1], sys.argv[2]
dataset = LeRobotDataset("r2d2-viz/export-test", root=root, video_backend="pyav")
columns: dict[str, list[np.ndarray]] = {}
for i in range(len(dataset)):
    item = dataset[i]
    for key, value in item.items():
        if hasattr(value, "numpy"):
            array = value.numpy()
            if key.startswith("observation.images."):
                array = np.round(array.transpose(1, 2, 0) * 255).clip(0, 255).astype(np.uint8)
            columns.setdefault(key, []).append(array)
    columns.setdefault("task", []).append(np.array(item["task"]))
meta = {
    "total_episodes": dataset.meta.total_episodes,
    "total_frames": dataset.meta.total_frames,
    "num_episodes": dataset.num_episodes,
    "fps": dataset.fps,
    "camera_keys": dataset.meta.camera_keys,
    "features": list(dataset.meta.features),
    "tasks": list(dataset.meta.tasks.index),
}
np.savez(out, meta=np.array(json.dumps(meta)), **{k: np.stack(v) for k, v in columns.items()})
print(json.dumps(meta))
