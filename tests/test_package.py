"""The ament_python package: manifest, install layout, entry point, and the import direction."""
import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest
from catkin_pkg.package import parse_package

pytestmark = pytest.mark.ros

REPO = Path(__file__).resolve().parents[1]


def test_package_xml_is_a_valid_format_3_ament_python_manifest():
    pkg = parse_package(str(REPO / "package.xml"))
    pkg.validate()
    assert pkg.package_format == 3
    assert pkg.name == "gpusph_ros"
    assert pkg.get_build_type() == "ament_python"
    deps = {d.name for d in pkg.exec_depends}
    assert {"rclpy", "sensor_msgs", "geometry_msgs", "std_msgs", "std_srvs", "rosgraph_msgs",
            "diagnostic_msgs"} <= deps


def _ros_imports(folder: Path) -> set:
    """The ROS packages the Python under ``folder`` imports: rclpy, ament_index_python, launch and
    launch_ros, and every <pkg> of a <pkg>.msg / <pkg>.srv import."""
    found = set()
    for path in folder.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = [node.module] if isinstance(node, ast.ImportFrom) and node.module else (
                [a.name for a in node.names] if isinstance(node, ast.Import) else [])
            for name in names:
                top, _, rest = name.partition(".")
                if top in ("rclpy", "ament_index_python", "launch", "launch_ros") or rest.split(".")[0] in ("msg",
                                                                                                        "srv"):
                    found.add(top)
    return found


def test_package_xml_declares_every_ros_package_the_code_and_launch_files_import():
    deps = {d.name for d in parse_package(str(REPO / "package.xml")).exec_depends}
    used = _ros_imports(REPO / "gpusph_ros") | _ros_imports(REPO / "launch")
    assert {"rclpy", "tf2_msgs", "visualization_msgs", "launch_ros"} <= used
    assert used <= deps, sorted(used - deps)


def test_setup_installs_the_ament_marker_manifest_and_config(tmp_path):
    out = subprocess.run([sys.executable, "setup.py", "--quiet", "install", "--root", str(tmp_path),
                          "--prefix", "/p", "--single-version-externally-managed",
                          "--record", str(tmp_path / "files.txt")],
                         cwd=REPO, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]
    prefix = tmp_path / "p"
    assert (prefix / "share/ament_index/resource_index/packages/gpusph_ros").is_file()
    assert (prefix / "share/gpusph_ros/package.xml").is_file()
    for cfg in (*(REPO / "config").rglob("*"), *(REPO / "data").rglob("*"), *(REPO / "launch").rglob("*"),
                *(REPO / "rviz").rglob("*"), *(REPO / "foxglove").rglob("*")):
        if cfg.is_file():
            assert (prefix / "share/gpusph_ros" / cfg.relative_to(REPO)).is_file(), cfg
    assert (prefix / "lib/gpusph_ros/sim_node").is_file()
    for script in ("gpusph-run", "gpusph-analyze", "gpusph-sweep", "gpusph-plan", "gpusph-stability"):
        assert (prefix / "lib/gpusph_ros" / script).is_file(), script
    # the installed package finds its scenes and run configurations under <prefix>/share
    site = next(prefix.glob("lib/python*/site-packages"))
    code = ("from gpusph_ros.scenes.schema import builtin_names; "
            "from gpusph_ros.scenes.settings import run_config_names; "
            "import gpusph_ros.share as s; print(s.config_dir('scenes')); print(builtin_names(), run_config_names()); "
            "from gpusph_ros.analysis.reference import data_dir; print(data_dir())")
    found = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True,
                           env={"PYTHONPATH": str(site), "PATH": "/usr/bin:/bin"})
    assert found.returncode == 0, found.stderr[-2000:]
    assert str(prefix / "share/gpusph_ros/config/scenes") in found.stdout
    assert "dambreak1_thesis" in found.stdout and "thesis_scenario1" in found.stdout
    assert str(prefix / "share/gpusph_ros/data") in found.stdout  # the reference tables, installed


def test_setup_cfg_puts_scripts_where_ros2_run_looks():
    text = (REPO / "setup.cfg").read_text()
    assert "script_dir=$base/lib/gpusph_ros" in text
    assert "install_scripts=$base/lib/gpusph_ros" in text


def test_solver_imports_nothing_from_ros():
    code = ("import sys, gpusph_ros.sph, gpusph_ros.scenes.boxes; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('rclpy', 'rosidl_runtime_py', 'sensor_msgs') "
            "or m.startswith('gpusph_ros.ros')]; print(bad); sys.exit(1 if bad else 0)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO)
    assert out.returncode == 0, out.stdout + out.stderr


def test_the_node_starts_without_the_mcap_package_until_it_records():
    """mcap is from PyPI only: the node, the runner, the parameter checks and a run load without it,
    and only opening a recording needs it."""
    code = ("import sys; sys.modules['mcap'] = None; import gpusph_ros.ros.sim_node, gpusph_ros.runner; "
            "import gpusph_ros.ros.node_params as p; assert p.check(p.DEFAULTS) is None; "
            "from gpusph_ros.scenes.schema import load_scene; from gpusph_ros.scenes.settings import resolve; "
            "scene = load_scene('collapse_2d'); run = gpusph_ros.runner.Run(scene, resolve(scene, dx=0.02)); "
            "print('loaded', flush=True); run.open_recording('unused')")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO)
    assert "loaded" in out.stdout, out.stderr[-2000:]
    assert out.returncode != 0 and "ModuleNotFoundError" in out.stderr and "mcap" in out.stderr.splitlines()[-1]


def test_the_runner_stands_below_the_node():
    """Layers point one way: the runner (and the output layer under it) import nothing of ros/."""
    code = ("import sys, gpusph_ros.runner, gpusph_ros.output.recording; "
            "bad = [m for m in sys.modules if m.startswith('gpusph_ros.ros')]; print(bad); sys.exit(1 if bad else 0)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO)
    assert out.returncode == 0, out.stdout + out.stderr


# package.xml's dependencies as PyPI has them (no rosdep key maps to a wheel): the interfaces that
# come with rclpy's wheel, those of common_interfaces, the Python libraries; None: no wheel (tf2_msgs,
# launch, RViz: a ROS 2 install's own, and the node runs without them)
PYPI = {"rclpy": "ros-jazzy-rclpy[fastrtps]", "builtin_interfaces": "ros-jazzy-rclpy[fastrtps]",
        "rcl_interfaces": "ros-jazzy-rclpy[fastrtps]", "lifecycle_msgs": "ros-jazzy-rclpy[fastrtps]",
        "rosgraph_msgs": "ros-jazzy-rclpy[fastrtps]", "sensor_msgs": "ros-jazzy-common-interfaces",
        "geometry_msgs": "ros-jazzy-common-interfaces", "std_msgs": "ros-jazzy-common-interfaces",
        "std_srvs": "ros-jazzy-common-interfaces", "diagnostic_msgs": "ros-jazzy-common-interfaces",
        "visualization_msgs": "ros-jazzy-common-interfaces", "nav_msgs": "ros-jazzy-common-interfaces",
        "python3-numpy": "numpy", "python3-yaml": "PyYAML",
        "python3-matplotlib": "matplotlib", "python3-tqdm": "tqdm", "tf2_msgs": None, "ament_index_python": None,
        "launch": None, "launch_ros": None, "launch_xml": None, "rviz2": None}


def test_a_clean_venv_from_the_declarations_alone_starts_the_node_and_records(tmp_path):
    """A new venv gets package.xml's dependencies (as PyPI names them) and the package with setup.py's
    install_requires, pinned by requirements.txt and nothing else; its installed sim_node runs the
    default scene to its end and writes a recording that rosbags reads."""
    import os
    import shutil
    import signal
    import time

    from rosbags.highlevel import AnyReader

    deps = [d.name for d in parse_package(str(REPO / "package.xml")).exec_depends]
    assert set(deps) <= set(PYPI), sorted(set(deps) - set(PYPI))  # a new dependency needs its PyPI name here
    wanted = sorted({PYPI[d] for d in deps if PYPI[d]})
    venv = tmp_path / "venv"
    try:
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        pins = tmp_path / "pins.txt"  # requirements.txt as constraints (which take no extras)
        pins.write_text(re.sub(r"\[[^\]]*\]", "", (REPO / "requirements.txt").read_text()))
        pip = [str(venv / "bin/python"), "-m", "pip", "install", "--quiet", "-c", str(pins)]
        out = subprocess.run([*pip, *wanted, str(REPO)], capture_output=True, text=True, timeout=900)
        assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-2000:]
        env = {"PATH": f"{venv / 'bin'}:/usr/bin:/bin", "HOME": str(tmp_path), "ROS_DOMAIN_ID": "97",
               "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "PYTHONUNBUFFERED": "1"}
        log = tmp_path / "node.log"
        with open(log, "w") as f:
            # pip puts console scripts in bin/ (colcon, reading setup.cfg, in lib/gpusph_ros/)
            node = subprocess.Popen([str(venv / "bin/sim_node"), "--ros-args", "-p", "dx:=0.06",
                                     "-p", "end_time:=0.05", "-p", f"record_dir:={tmp_path / 'bags'}"],
                                    cwd=tmp_path, env=env, stdout=f, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 300
        while "reached end_time" not in log.read_text() and node.poll() is None and time.monotonic() < deadline:
            time.sleep(0.5)
        node.send_signal(signal.SIGINT)
        node.wait(timeout=60)
        text = log.read_text()
        assert "reached end_time = 0.05 s" in text, text[-3000:]
        bag = next((tmp_path / "bags").iterdir())
        with AnyReader([bag]) as reader:
            topics = {c.topic for c in reader.connections}
            assert reader.message_count == sum(1 for _ in reader.messages())
        assert {"/clock", "/sim_node/particles", "/sim_node/scene"} <= topics
        assert not any(line.startswith("Traceback") for line in text.splitlines()), text[-3000:]
    finally:
        shutil.rmtree(venv, ignore_errors=True)  # 0.7 GB
        os.sync()
