"""The launch files, the RViz view and the Foxglove layout the package installs: they parse, and
every topic, message type, field, frame and parameter they name is one the node has. (launch,
RViz and Foxglove themselves are not installable here: no wheels.) What the node publishes is read
from a recording of the default scene, which holds every topic the node publishes for it, and
from its export's reference bag."""
import ast
import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import yaml
from rosbags.highlevel import AnyReader

from gpusph_ros.analysis.bag import message_class
from gpusph_ros.analysis.export import export
from gpusph_ros.ros.node_params import BY_NAME, DEFAULTS
from gpusph_ros.runner import Run
from gpusph_ros.scenes.schema import load_scene
from gpusph_ros.scenes.settings import resolve

pytestmark = pytest.mark.unit

REPO = Path(__file__).resolve().parents[1]
RVIZ_TYPES = {"rviz_default_plugins/PointCloud2": "sensor_msgs/msg/PointCloud2",
              "rviz_default_plugins/MarkerArray": "visualization_msgs/msg/MarkerArray"}


@pytest.fixture(scope="module")
def published(tmp_path_factory, reference_data):
    """{topic: type} of a recording of the node's default scene and of its export, and the cloud's fields."""
    tmp = tmp_path_factory.mktemp("viewers")
    scene = load_scene(DEFAULTS["scene"])
    run = Run(scene, resolve(scene, sets=["dx=0.06", "end_time=0.05", "particle_rate=100"]))
    run.execute(run.open_recording(tmp / "bag"))
    topics = {}
    for bag in (tmp / "bag", Path(export(tmp / "bag", tmp / "export", reference_data)["bag"])):
        with AnyReader([bag]) as reader:
            topics |= {c.topic: c.msgtype for c in reader.connections}
    return topics, run.packer.fields


def _field_path_exists(type_name: str, path: str) -> bool:
    value = message_class(type_name)()
    for name in path.split("."):
        if not hasattr(value, name):
            return False
        value = getattr(value, name)
    return True


def test_the_rviz_view_names_what_the_node_publishes(published):
    topics, fields = published
    view = yaml.safe_load((REPO / "rviz/sim.rviz").read_text())
    manager = view["Visualization Manager"]
    assert manager["Global Options"]["Fixed Frame"] == DEFAULTS["frame_id"] == "world"
    shown = 0
    for display in manager["Displays"]:
        if display["Class"] not in RVIZ_TYPES:
            continue
        topic = display["Topic"]["Value"]
        assert topics.get(topic) == RVIZ_TYPES[display["Class"]], topic
        # a latched topic needs a transient-local subscription to be received after it was sent
        latched = topic in ("/sim_node/geometry", "/sim_node/scene")
        assert display["Topic"]["Durability Policy"] == ("Transient Local" if latched else "Volatile"), topic
        if "Channel Name" in display:
            assert display["Channel Name"] in fields
        shown += 1
    assert shown == 4
    assert {d["Channel Name"] for d in manager["Displays"] if "Channel Name" in d} == {"pressure", "kind"}


def test_the_foxglove_layout_names_what_the_node_and_the_export_publish(published):
    topics, fields = published
    layout = json.loads((REPO / "foxglove/sim.json").read_text())
    panels = layout["configById"]
    three_d = panels["3D!sim"]
    assert three_d["followTf"] == "world"
    for topic, settings in three_d["topics"].items():
        assert topic in topics, topic
        if "colorField" in settings:
            assert settings["colorField"] in fields
    plotted = [p["value"] for key, panel in panels.items() if key.startswith("Plot!") for p in panel["paths"]]
    assert any(p.startswith("/reference/") for p in plotted)
    for value in plotted:
        topic, _, path = value.partition(".")
        assert topic in topics, topic
        assert _field_path_exists(topics[topic], path), value

    def leaves(node):
        return [node] if isinstance(node, str) else leaves(node["first"]) + leaves(node["second"])

    assert sorted(leaves(layout["layout"])) == sorted(panels)


def _python_launch():
    tree = ast.parse((REPO / "launch/sim.launch.py").read_text())
    calls = [n for n in ast.walk(tree) if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)]
    arguments = {c.args[0].value: {k.arg: k.value for k in c.keywords} for c in calls
                 if c.func.id == "DeclareLaunchArgument"}
    nodes = [{k.arg: k.value for k in c.keywords} for c in calls if c.func.id == "Node"]
    return tree, arguments, nodes


def test_the_launch_file_starts_sim_node_with_declared_parameters_and_the_shared_files():
    tree, arguments, nodes = _python_launch()
    assert {n.name for n in tree.body if isinstance(n, ast.FunctionDef)} == {"generate_launch_description"}
    sim = next(n for n in nodes if n["executable"].value == "sim_node")
    assert sim["package"].value == "gpusph_ros"
    params = [d for d in sim["parameters"].elts if isinstance(d, ast.Dict)][0]
    names = [k.value for k in params.keys]
    assert set(names) <= set(BY_NAME) and set(names) <= set(arguments)
    assert set(arguments) == {"scene", "dx", "params_file", "record_dir", "rviz"}
    assert arguments["scene"]["default_value"].value == DEFAULTS["scene"]
    assert float(arguments["dx"]["default_value"].value) == DEFAULTS["dx"]
    # the files it names lie where setup.py installs them (share/gpusph_ros/<folder>)
    strings = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)}
    assert {"config", "sim_node.yaml", "rviz", "sim.rviz"} <= strings
    assert (REPO / "config/sim_node.yaml").is_file() and (REPO / "rviz/sim.rviz").is_file()
    rviz = next(n for n in nodes if n["executable"].value == "rviz2")
    assert rviz["package"].value == "rviz2"


def test_the_xml_launch_twin_has_the_same_arguments_and_parameters():
    _, arguments, _ = _python_launch()
    root = ET.parse(REPO / "launch/sim.launch.xml").getroot()
    assert root.tag == "launch"
    args = {a.get("name"): a.get("default") for a in root.findall("arg")}
    assert set(args) == set(arguments)
    for name in ("scene", "dx", "record_dir", "rviz"):
        assert args[name] == arguments[name]["default_value"].value, name
    assert args["params_file"] == "$(find-pkg-share gpusph_ros)/config/sim_node.yaml"
    sim = next(n for n in root.findall("node") if n.get("exec") == "sim_node")
    assert sim.get("pkg") == "gpusph_ros" and sim.get("name") == "sim_node"
    named = {p.get("name"): p for p in sim.findall("param") if p.get("name")}
    assert set(named) <= set(BY_NAME) and {p.get("from") for p in sim.findall("param") if p.get("from")} == {
        "$(var params_file)"}
    types = {float: "float", str: "str"}
    for name, p in named.items():  # typed as the node declares them (dx:=1 must arrive as a double)
        assert p.get("type") == types[type(DEFAULTS[name])], name
    rviz = next(n for n in root.findall("node") if n.get("exec") == "rviz2")
    assert "rviz/sim.rviz" in rviz.get("args") and rviz.get("if") == "$(var rviz)"
