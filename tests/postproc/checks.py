"""The checks of the report's test scripts: each prints "ok:" or "FAIL:" and its sentence, and a
failed one is kept in FAILS, which the script counts at its end (exit 1 when any failed)."""

FAILS = []


def check(cond, what):
    print(("ok:   " if cond else "FAIL: ") + what)
    if not cond:
        FAILS.append(what)
    return cond
