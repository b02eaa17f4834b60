"""Benchmark: the simulator's real-time factor at 1 kHz, as fast as possible (real_time_factor 0),
10 steps of the default gait, planner and simulator as real node processes, with every topic
published and recorded, and with recording off; beside it, in the same run, the walker alone
(integration, events, double supports, samples, the node's default re-aim with momentum
steering: no world view, no ROS), the walker with the
world view and the messages serialized (no ROS), the straightforward cold solve (the machine's
yardstick, ``yardsticks.ColdSolve``: the node's factor is also given as it would be on the
reference machine) and the cost of one message each way. Each real-time factor is the median of
``--repeat`` runs (their range beside it), the runs interleaved with cold solves: the machine is
shared, and a run's figure moves with the load. Run:

    .venv/bin/python benchmarks/bench_simulator.py [--steps N] [--repeat N]
"""

from __future__ import annotations

import argparse
import io
import math
import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_DOMAIN_ID", "92")

import rclpy  # noqa: E402
from mcap.writer import Writer  # noqa: E402
from rclpy.serialization import serialize_message  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402

from biped_gait.core.gait.planner import GaitPlanner, GaitRequest  # noqa: E402
from biped_gait.core.dynamics.samples import NativeSamples  # noqa: E402
from biped_gait.core.model.params import load_params  # noqa: E402
from biped_gait.core.walking.steering import DEFAULT_RATE  # noqa: E402
from biped_gait.core.walking.events import StepSamples  # noqa: E402
from biped_gait.core.walking.orbit import PlannedOrbit  # noqa: E402
from biped_gait.core.walking.runner import Walker  # noqa: E402
from biped_gait.core.walking.walk import Walk  # noqa: E402
from biped_gait.recording.background import BackgroundRecorder  # noqa: E402
from biped_gait.recording.writer import McapRecorder  # noqa: E402
from biped_gait.ros.walk_messages import SampleMessages  # noqa: E402
import results  # noqa: E402
from harness import RATE, median_range, simulator_factor  # noqa: E402
from yardsticks import ColdSolve, at_reference, median_s  # noqa: E402

REQUEST = GaitRequest(0.45, 0.45, math.radians(23.5), "normal")


def per_call_us(call, count: int = 20000) -> float:
    """Mean wall time of ``call()`` (us) over ``count`` calls."""
    start = time.perf_counter()
    for _ in range(count):
        call()
    return 1e6 * (time.perf_counter() - start) / count


def core_factors(planner: GaitPlanner, steps: int) -> tuple[float, float]:
    """Real-time factors of the walker alone, and of the walk's step batches with the world view
    and every sampled message serialized (what the node does before publishing); both walk as the
    node does by default (re-aim with momentum steering at ``DEFAULT_RATE``)."""
    orbit = PlannedOrbit.of(planner.plan(REQUEST))
    walker = Walker(planner.hybrid, orbit, RATE, momentum_rate=DEFAULT_RATE)
    start = time.perf_counter()
    for _ in range(steps):
        walker.walk_step()
    walker_rtf = walker.state.t / (time.perf_counter() - start)
    walk = Walk(orbit, RATE, steps, momentum_rate=DEFAULT_RATE)
    messages = SampleMessages(walk.world.joints.names, walk.world.link_frames)
    start, simulated = time.perf_counter(), 0.0
    for item in walk.batches():
        if isinstance(item, StepSamples):
            messages.encode(item.world, (item.t * 1e9).astype(np.int64), 0, item.samples[0].stance_side)
            simulated = item.samples[-1].t + 1.0 / RATE
    return walker_rtf, simulated / (time.perf_counter() - start)


def message_costs(tmp: Path) -> dict[str, float]:
    """Per-message costs (us): a JointState built, serialized, published as a message and as
    bytes; an MCAP add_message (raw writer); a step of messages serialized from the templates
    (per sample, 4 topics); a message queued for the recorder's writer thread."""
    rclpy.init()
    node = rclpy.create_node("bench_messages")
    publisher = node.create_publisher(JointState, "/bench_joint_states", 50)
    names = list(load_params().joints.physical_names())
    build = lambda: JointState(name=names, position=[0.1] * 7, velocity=[0.2] * 7,  # noqa: E731
                               effort=[0.0] * 7)
    msg = build()
    data = serialize_message(msg)
    writer = Writer(io.BytesIO())
    writer.start(profile="ros2")
    channel = writer.register_channel("/j", "cdr", writer.register_schema("sensor_msgs/msg/JointState", "ros2msg", b""))
    recorder = BackgroundRecorder(McapRecorder(tmp, "bench_bag"))
    recorder.add_topic("/j", "sensor_msgs/msg/JointState", [])
    planner = GaitPlanner()
    walk = Walk(PlannedOrbit.of(planner.plan(REQUEST)), RATE, 1)
    step = next(item for item in walk.batches() if isinstance(item, StepSamples))
    messages = SampleMessages(walk.world.joints.names, walk.world.link_frames)
    stamps = (step.t * 1e9).astype(np.int64)
    costs = {
        "JointState built": per_call_us(build),
        "serialize_message (JointState)": per_call_us(lambda: serialize_message(msg)),
        "publish (message)": per_call_us(lambda: publisher.publish(msg)),
        "publish (serialized bytes)": per_call_us(lambda: publisher.publish(data)),
        "MCAP add_message (raw writer)": per_call_us(lambda: writer.add_message(channel, 1, data, 1)),
        "recorder write (queued)": per_call_us(lambda: recorder.write("/j", data, 1)),
        "templates, 4 topics per sample": per_call_us(lambda: messages.encode(step.world, stamps, 0, "right"), 200)
        / len(stamps),
    }
    recorder.close()
    node.destroy_node()
    rclpy.shutdown()
    return costs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    planner = GaitPlanner()
    yardstick = ColdSolve()
    yardstick.solve()
    walker, encoded, recorded, unrecorded, colds = [], [], [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        where = Path(tmp)
        for run in range(args.repeat):  # interleaved, so that a change of load falls on all alike
            walker_rtf, encoded_rtf = core_factors(planner, args.steps)
            walker.append(walker_rtf)
            encoded.append(encoded_rtf)
            recorded.append(simulator_factor(where / f"run{run}", args.steps, ["record:=true"], "on"))
            unrecorded.append(simulator_factor(where / f"run{run}", args.steps, ["record:=false"], "off"))
            colds.extend(median_s(yardstick.solve, 1) for _ in range(2))
        costs = message_costs(where)
    simulated = args.steps * REQUEST.period
    median = statistics.median
    cold = median(colds)
    print(f"simulator at {RATE:g} Hz, {args.steps} steps ({simulated:.2f} s simulated), as fast as possible, "
          f"median of {args.repeat} runs [range]; the straightforward cold solve: {1e3 * cold:.1f} ms (median)")
    print(f"  node, every topic published and recorded: real-time factor {median_range(recorded)}; on the reference machine "
          f"{at_reference(median(recorded), cold):.1f}")
    print(f"  node, published, recording off:           real-time factor {median_range(unrecorded)}")
    print(f"  walker alone (no world view, no ROS):     real-time factor {median_range(walker)}; "
          f"node with recording / walker alone = {median(recorded) / median(walker):.2f}")
    print(f"  walker + world view + messages serialized (no ROS): real-time factor {median_range(encoded)}")
    print(f"  (samples evaluated {'in the compiled twin' if NativeSamples is not None else 'by the Python loops'})")
    print("per message (us):")
    for what, cost in costs.items():
        print(f"  {what:34s} {cost:7.2f}")
    results.write("bench_simulator", {
        "node, recording": f"{median(recorded):.1f}", "walker alone": f"{median(walker):.1f}",
        "node, recording / walker alone": f"{median(recorded) / median(walker):.2f}",
        "node, recording, at the reference speed": f"{at_reference(median(recorded), cold):.1f}"},
        {"recorded": recorded, "unrecorded": unrecorded, "walker": walker, "encoded": encoded, "cold_solve_s": cold},
        {"rate (Hz)": round(RATE), "steps": args.steps, "runs": args.repeat})


if __name__ == "__main__":
    main()
