"""tap.py - TAP output for the Python tests beside it: one line a check,
the detail of a failing one as comments, and the plan at the end."""

counts = {"run": 0, "failed": 0}


def check(ok, what, detail=""):
    counts["run"] += 1
    if not ok:
        counts["failed"] += 1
    print(("ok %d - " if ok else "not ok %d - ") % counts["run"] + what)
    if not ok:
        for line in detail.splitlines()[:8]:
            print("# " + line)


def finish():
    """Prints the plan; the exit status for sys.exit."""
    print("1..%d" % counts["run"])
    return 1 if counts["failed"] else 0
