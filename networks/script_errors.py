"""What the training scripts share for refusing bad input: one line `SCRIPT: error: ...` on stderr and
exit 1 (a bad or missing file) or 2 (a usage error), never a traceback; and the --resume check that a
checkpoint is continued only under the options it was trained with.
"""
import os
import sys


class ScriptError(Exception):
    """A refusal: message (one line) and exit code (1: bad or missing file; 2: usage error; 3: Ctrl-C,
    docs/exit-codes.md; dataset.py passes on dynsky's own code)."""

    def __init__(self, message, code=1):
        super().__init__(message)
        self.code = code


def fail(message, code=1):
    raise ScriptError(message, code)


def run_main(script, func, argv=None):
    """Calls func(argv); a ScriptError becomes `SCRIPT: error: MESSAGE` on stderr and its exit code."""
    try:
        return func(argv)
    except ScriptError as e:
        print(f"{script}: error: {e}", file=sys.stderr)
        sys.exit(e.code)


def load_checkpoint(path, what="checkpoint"):
    """torch.load with a one-line refusal for a missing, truncated or foreign file."""
    import torch
    if not os.path.exists(path):
        fail(f"{path}: no such {what}")
    try:
        ck = torch.load(path)
    except Exception as e:  # truncated zip, not a torch file, pickle error...
        fail(f"{path}: not a readable PyTorch {what} ({type(e).__name__}: {str(e).splitlines()[0] if str(e) else 'no detail'})")
    if not isinstance(ck, dict) or "model" not in ck:
        fail(f"{path}: not a {what} of the dynsky training scripts (no 'model' entry)")
    return ck


def _norm(key, value):
    if key == "data" and isinstance(value, str) and value:
        return os.path.realpath(value)
    return value


def check_resume_args(ckpt_path, stored, args, defaults, ignore):
    """Refuses (exit 2) when an option that defines the model or the run differs from the one the
    checkpoint at ckpt_path was trained with. stored: the checkpoint's args (a dict, or None for a
    checkpoint that kept none); defaults: the parser's defaults, standing for options an older
    checkpoint did not store; ignore: the options a resume may change (--epochs, operational ones)."""
    if stored is None:
        return
    new = vars(args)
    diffs = []
    for key in sorted(set(new) | set(stored)):
        if key in ignore:
            continue
        old_v = stored.get(key, defaults.get(key))
        new_v = new.get(key, defaults.get(key))
        if _norm(key, old_v) != _norm(key, new_v):
            diffs.append(f"--{key.replace('_', '-')} {old_v!r} -> {new_v!r}")
    if diffs:
        fail(f"--resume: {ckpt_path} was trained with other options: {'; '.join(diffs)} "
             "(resume with the checkpoint's options, or train into a new --out)", 2)


def resume_checkpoint(ckpt_path, args, parser, may_change):
    """The checkpoint a --resume continues (None without --resume): refused when it is missing or
    was trained with other options than those a resume may change (check_resume_args)."""
    if not args.resume:
        return None
    if not os.path.exists(ckpt_path):
        fail(f"--resume: {ckpt_path}: no checkpoint to resume (train without --resume to start this run)")
    ck = load_checkpoint(ckpt_path)
    check_resume_args(ckpt_path, ck.get("args"), args, {a.dest: a.default for a in parser._actions}, may_change)
    return ck
