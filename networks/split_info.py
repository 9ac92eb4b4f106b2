"""What a data set's split.json says beyond frame numbers (dataset.py, build_dataset_v2.py)."""


def photographs_trained(meta, train_end):
    """Which photographs of a real sequence the split trains on, by name and capture time, so that
    `dynsky sky evaluate` finds them wherever they are scored (frame numbers number this data set's
    own folder, which need not be the whole shared sequence)."""
    if not meta.get("preset"):
        return {}  # procedural: no photographs
    out = {"preset": meta["preset"], "trained_photos": list(meta.get("frames", []))[:train_end]}
    utc = [u for u in (meta.get("frames_utc_s") or [])[:train_end] if u is not None]
    if utc:
        out["trained_utc_s"] = [min(utc), max(utc)]
    return out


def same_split(a, b):
    """The fixed part of a split (frame ranges and cadence); names and times may be added later."""
    keys = ("train", "heldout", "fit", "val", "dt_s")
    return all(a.get(k) == b.get(k) for k in keys)
