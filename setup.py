"""biped_gait: an ament_python package, installable with pip (entry points below)."""

from setuptools import find_packages, setup

PACKAGE = "biped_gait"

setup(
    name=PACKAGE,
    version="0.1.0",
    description="Ballistic walking gaits of a 3D seven-link biped with swinging arms",
    license="Apache-2.0",
    python_requires=">=3.11",
    packages=find_packages(include=[PACKAGE, f"{PACKAGE}.*"]),
    package_data={f"{PACKAGE}.core.data": ["*.yaml", "atlas/*.npz", "stop/*.npz", "start/*.npz"]},
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/config", ["config/demo.yaml"]),
    ],
    install_requires=["numpy", "scipy", "pin", "osqp", "highspy", "PyYAML"],
    entry_points={
        "console_scripts": [
            "biped-gait = biped_gait.cli:main",
            "biped-gait-planner = biped_gait.ros.planner_node:main",
            "biped-gait-simulator = biped_gait.ros.simulator_node:main",
            "biped-gait-replay = biped_gait.ros.replay:main",
            "biped-gait-analyze = biped_gait.analysis.cli:main",
            "biped-gait-launch = biped_gait.ros.launch:main",
        ],
    },
)
