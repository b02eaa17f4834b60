"""The package a ROS workspace builds: package.xml lists every ROS package the code imports (and
none it does not), every Python library by its rosdep key (and requirements.txt pins it),
setup.cfg installs the entry points where ``ros2 run`` looks, and the interface packages of
msg_defs/ declare (package.xml and CMake) every package their definitions use and every file."""

from __future__ import annotations

import ast
import configparser
import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

pytestmark = pytest.mark.core

ROOT = Path(__file__).resolve().parents[1]
AMENT_INDEX = Path(sys.prefix) / "share" / "ament_index" / "resource_index" / "packages"
# Python libraries the code imports: their rosdep key and their distribution in requirements.txt.
LIBRARIES = {
    "numpy": ("python3-numpy", "numpy"), "scipy": ("python3-scipy", "scipy"), "yaml": ("python3-yaml", "PyYAML"),
    "matplotlib": ("python3-matplotlib", "matplotlib"), "tqdm": ("python3-tqdm", "tqdm"),
    "pinocchio": ("pinocchio", "pin"), "highspy": ("python3-highspy-pip", "highspy"),
    "osqp": ("python3-osqp-pip", "osqp"), "mcap": ("python3-mcap-pip", "mcap"),
    "mcap_ros2": ("python3-mcap-ros2-support-pip", "mcap-ros2-support"),
    "distributed": ("python3-distributed-pip", "distributed"), "foxglove": ("python3-foxglove-sdk-pip", "foxglove-sdk"),
    "mujoco": ("python3-mujoco-pip", "mujoco"), "casadi": ("python3-casadi-pip", "casadi"),
    "joblib": ("python3-joblib", "joblib"),
}


def imported_modules(folder: Path) -> set[str]:
    """Top-level names of the absolute imports of every module under ``folder``."""
    names = set()
    for path in folder.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names.update(alias.name.split(".")[0] for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names.add(node.module.split(".")[0])
    return names


def depends(manifest: Path, *kinds: str) -> set[str]:
    root = ET.parse(manifest).getroot()
    assert root.get("format") == "3", manifest
    return {element.text.strip() for kind in kinds for element in root.iter(kind)}


def test_package_xml_lists_every_ros_package_and_library_the_code_imports():
    assert AMENT_INDEX.is_dir(), "the venv is no ROS prefix (tools/setup.sh)"
    imported = imported_modules(ROOT / "biped_gait") - {"biped_gait"}
    ros = {name for name in imported if (AMENT_INDEX / name).exists()}
    others = imported - ros - set(sys.stdlib_module_names)
    listed = depends(ROOT / "package.xml", "depend", "exec_depend")
    assert {"rclpy", "biped_gait_interfaces", "diagnostic_msgs", "tf2_msgs"} <= ros
    assert ros <= listed, f"imported but not in package.xml: {sorted(ros - listed)}"
    assert others <= set(LIBRARIES), f"libraries without a rosdep key here: {sorted(others - set(LIBRARIES))}"
    keys = {LIBRARIES[name][0] for name in others}
    assert keys <= listed, f"libraries not in package.xml: {sorted(keys - listed)}"
    ros_listed = {name for name in listed if (AMENT_INDEX / name).exists()}
    assert ros_listed == ros, f"in package.xml but not imported: {sorted(ros_listed - ros)}"
    assert listed - ros_listed == {LIBRARIES[name][0] for name in others}, "a library listed that the code does not use"
    pinned = {re.split(r"==", line)[0].lower() for line in (ROOT / "requirements.txt").read_text().splitlines()
              if "==" in line and not line.startswith("#")}
    missing = {LIBRARIES[name][1] for name in others if LIBRARIES[name][1].lower() not in pinned}
    assert not missing, f"not pinned in requirements.txt: {sorted(missing)}"


def test_the_workspace_installs_the_entry_points_where_ros2_run_looks():
    root = ET.parse(ROOT / "package.xml").getroot()
    assert root.findtext("name") == "biped_gait" and root.find("export").findtext("build_type") == "ament_python"
    config = configparser.ConfigParser(interpolation=None)
    config.read(ROOT / "setup.cfg")
    assert config["develop"]["script_dir"] == config["install"]["install_scripts"] == "$base/lib/biped_gait"
    setup = (ROOT / "setup.py").read_text()
    assert 'PACKAGE = "biped_gait"' in setup and '"share/ament_index/resource_index/packages"' in setup
    assert (ROOT / "resource" / "biped_gait").is_file()
    for module, function in re.findall(r'"biped-gait[\w-]* = ([\w.]+):(\w+)"', setup):
        source = (ROOT / Path(*module.split("."))).with_suffix(".py").read_text()
        assert f"def {function}(" in source, (module, function)


@pytest.mark.parametrize("package", ["biped_gait_interfaces", "tf2_msgs"])
def test_each_interface_package_declares_what_its_definitions_use(package):
    folder = ROOT / "msg_defs" / package
    files = sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.suffix in (".msg", ".srv", ".action"))
    used = set()
    for name in files:
        for line in (folder / name).read_text().splitlines():
            field = line.split("#")[0].split()
            if field and "/" in field[0]:
                used.add(field[0].split("/")[0])
    if any(name.endswith(".action") for name in files):
        used |= {"action_msgs", "builtin_interfaces"}  # what rosidl's actions are made of
    assert "biped_gait_interfaces" not in used or package == "biped_gait_interfaces"
    used.discard(package)
    listed = depends(folder / "package.xml", "depend", "build_depend")
    assert used <= listed, f"{package}/package.xml lacks {sorted(used - listed)}"
    assert {"rosidl_default_generators"} <= depends(folder / "package.xml", "buildtool_depend")
    assert "rosidl_default_runtime" in depends(folder / "package.xml", "exec_depend")
    assert ET.parse(folder / "package.xml").getroot().findtext("member_of_group") == "rosidl_interface_packages"
    cmake = (folder / "CMakeLists.txt").read_text()
    generated = re.search(r"rosidl_generate_interfaces\((.*?)\)", cmake, re.S).group(1)
    assert sorted(re.findall(r'"([^"]+)"', generated)) == files, "a definition not generated, or one missing"
    declared = set(re.search(r"DEPENDENCIES([^)]*)", generated).group(1).split())
    assert used <= declared and all(f"find_package({name} REQUIRED)" in cmake for name in used)
