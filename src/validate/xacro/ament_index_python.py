"""The ROS 2 package index as the harness sees it, for xacro.

xacro resolves `$(find PKG)` with
`ament_index_python.packages.get_package_share_directory`. The harness
writes this module first on xacro's PYTHONPATH, with the packages it finds
([model] packages, the URDF's own package.xml, ROS_PACKAGE_PATH,
AMENT_PREFIX_PATH) in the file named by ANHOLONOMY_XACRO_PACKAGES, one
`name<TAB>directory` per line. A package it does not know is written to
the file named by ANHOLONOMY_XACRO_ABSENT (with the file xacro was reading)
and answered with a directory that does not exist, the name in brackets:
xacro reads such an include as a pattern that matches nothing, so the
expansion goes on and the harness names every absent package at once.
"""

import os
import pathlib
import sys

__all__ = [
    "PackageNotFoundError",
    "get_package_prefix",
    "get_package_share_directory",
    "get_package_share_path",
    "get_packages_with_prefixes",
]

ABSENT_ROOT = "/anholonomy-absent-package"


class PackageNotFoundError(KeyError):
    pass


def _packages():
    out = {}
    path = os.environ.get("ANHOLONOMY_XACRO_PACKAGES")
    if path:
        with open(path, encoding="utf-8") as f:
            for line in f:
                name, _, directory = line.rstrip("\n").partition("\t")
                out.setdefault(name, directory)
    return out


def _absent(package_name):
    xacro = sys.modules.get("xacro")
    stack = getattr(xacro, "filestack", None) or [None]
    where = stack[-1] or ""
    path = os.environ.get("ANHOLONOMY_XACRO_ABSENT")
    if not path:
        raise PackageNotFoundError(
            "package '{}' not found".format(package_name)
        )
    with open(path, "a", encoding="utf-8") as f:
        f.write("{}\t{}\n".format(package_name, where))
    return "{}/[{}]".format(ABSENT_ROOT, package_name)


def get_package_share_directory(package_name, print_warning=True):
    found = _packages().get(package_name)
    return found if found is not None else _absent(package_name)


def get_package_share_path(package_name, print_warning=True):
    return pathlib.Path(get_package_share_directory(package_name, print_warning))


def get_package_prefix(package_name):
    share = get_package_share_directory(package_name)
    parent = os.path.dirname(share)
    # An installed package sits at PREFIX/share/NAME.
    if os.path.basename(parent) == "share":
        return os.path.dirname(parent)
    return share


def get_packages_with_prefixes():
    return {name: get_package_prefix(name) for name in _packages()}
