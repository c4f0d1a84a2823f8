"""Shared by the plugin's tests: Mitsuba (scalar_rgb) with the macrofacet plugin registered, and
a PASS/FAIL tally."""

#: ctest's SKIP_RETURN_CODE for these tests.
SKIPPED = 77


def mitsuba_with_plugin():
    """The mitsuba module in scalar_rgb with the plugin registered, or None (after printing why the
    test is skipped) when Mitsuba is not installed."""
    try:
        import mitsuba as mi
    except ImportError:
        print("skipped: Mitsuba 3 is not installed (MF_SETUP_MITSUBA=1 scripts/setup.sh installs 3.9.1)")
        return None
    import macrofacet_mitsuba  # noqa: F401  (registers the plugin folder with Mitsuba's file resolver)
    mi.set_variant("scalar_rgb")
    mi.set_log_level(mi.LogLevel.Error)
    return mi


class Checks:
    """check(ok, what) prints [PASS]/[FAIL] what; .failed counts the failures; .exit_status()."""

    def __init__(self):
        self.failed = 0

    def __call__(self, ok, what):
        print(f'[{"PASS" if ok else "FAIL"}] {what}', flush=True)
        self.failed += not ok
        return ok

    def exit_status(self):
        print(f"{self.failed} failed")
        return 1 if self.failed else 0
