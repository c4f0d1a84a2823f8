"""macrofacet for Mitsuba 3: ``import macrofacet_mitsuba`` makes ``<medium type="macrofacet">``
loadable in the Mitsuba 3.9.1 that Python imports (scalar_rgb), then scenes load as usual::

    import mitsuba as mi
    import macrofacet_mitsuba
    mi.set_variant("scalar_rgb")
    image = mi.render(mi.load_file("scenes/mitsuba/thin_shell_sphere.xml"))

Mitsuba finds plugins as ``plugins/<name>.so`` through its file resolver; importing this package
appends the package's folder (which holds ``plugins/macrofacet.so``) to it, once.

``write_enclosure`` (and ``python3 -m macrofacet_mitsuba enclosure``) writes the boundary a mesh
mean surface needs: a closed mesh around the region f < k sigma, computed by the library
(mf_surface_enclosure). See the project README, section "Use in Mitsuba 3".
"""
import os

import mitsuba as mi

PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__))
#: The folder that holds macrofacet.so.
PLUGIN_DIR = os.path.join(PACKAGE_DIR, "plugins")


def register():
    """Appends this package's folder to Mitsuba's file resolver (idempotent). Called on import."""
    if not os.path.isfile(os.path.join(PLUGIN_DIR, "macrofacet.so")):
        raise ImportError(f"macrofacet_mitsuba: {PLUGIN_DIR}/macrofacet.so is missing (build the project with CMake: "
                          "the Mitsuba plugin is built when python3 finds mitsuba 3.9.1 and nanobind)")
    resolver = mi.file_resolver()
    if PACKAGE_DIR not in [str(p) for p in resolver]:
        resolver.append(PACKAGE_DIR)


register()

from .enclosure import write_enclosure  # noqa: E402  (needs nothing from Mitsuba's variants)

__all__ = ["PACKAGE_DIR", "PLUGIN_DIR", "register", "write_enclosure"]
