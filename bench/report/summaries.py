"""The runs of a bench: each sdf_tracker_offline output folder's summary.json, by folder name."""
import json
import os


def load(runs_dir):
    """{folder name: summary} for every folder under runs_dir that holds a summary.json."""
    runs = {}
    for name in sorted(os.listdir(runs_dir)):
        path = os.path.join(runs_dir, name, "summary.json")
        if os.path.isfile(path):
            with open(path) as f:
                runs[name] = json.load(f)
    return runs
