"""Prints where the Mitsuba 3 and Dr.Jit wheels and the nanobind headers are, as CMake
`set()` lines for mitsuba_plugin/CMakeLists.txt; on failure one line `set(MF_MI_ERROR "...")`.
Imports nothing that starts a Mitsuba variant."""
import importlib.util, os, sys


def main():
    found = {}
    for name in ("mitsuba", "drjit", "nanobind"):
        spec = importlib.util.find_spec(name)
        if spec is None or not spec.submodule_search_locations:
            hint = "pip install nanobind==2.14.0" if name == "nanobind" else "pip install mitsuba==3.9.1"
            return fail(f"the Python package '{name}' is not installed ({hint}, or MF_SETUP_MITSUBA=1 scripts/setup.sh)")
        found[name] = list(spec.submodule_search_locations)[0]
    import mitsuba
    import nanobind
    out = {
        "MF_MI_VERSION": mitsuba.__version__,
        "MF_MI_DIR": found["mitsuba"],
        "MF_DRJIT_DIR": found["drjit"],
        "MF_NANOBIND_INCLUDE": nanobind.include_dir(),
        "MF_NANOBIND_VERSION": nanobind.__version__,
        "MF_ROBIN_MAP_INCLUDE": os.path.join(found["nanobind"], "ext", "robin_map", "include"),
        "MF_MI_SITE_PACKAGES": os.path.dirname(found["mitsuba"]),
    }
    for k, v in out.items():
        print(f'set({k} "{v}")')
    return 0


def fail(msg):
    print(f'set(MF_MI_ERROR "{msg}")')
    return 0


if __name__ == "__main__":
    sys.exit(main())
