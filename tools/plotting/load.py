"""Reading the inputs: CSV rows, a study's records (its .jsonl where there is one), numbers."""
import csv
import json
import os


def num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def read_study(path):
    base, ext = os.path.splitext(path)
    jsonl = base + ".jsonl"
    if os.path.exists(jsonl):
        rows = []
        with open(jsonl) as f:
            for line in f:
                try:
                    rows.append(json.loads(line))
                except json.JSONDecodeError:
                    pass
        return rows
    return read_csv(path)
