"""Benchmark: the planner service's round trip from a client in another process, beside bare
rclpy services measured in the same run (nodes of a few lines spun by ``spin_once`` loops: one
answering std_srvs/Trigger, one answering PlanGait with the same response as the planner's, made
once; and its twin, the same code in a second process: how far two alike processes differ), one
call of each in turn, the order rotated each round (and the bare services and the cached plans also each alone,
back to back): a cached request and uncached ones (each a different arm amplitude), with the
planner recording and not, the whole plan and the plan without its trajectory's points
(``omit_trajectory``, 1.3 kB instead of 26 kB), median and p99 over ``--calls`` calls each
(``--uncached-calls`` for the uncached); then the same cached calls with the recording planner
stopped (its recording shares the two cores with the other servers). The first request of ``--fresh`` freshly started
planners (uncached, sent as soon as the service is found and has refused a bad request) beside their next uncached ones. Also
the client's and the server's share of the plan's size: one PlanGait response serialized and
deserialized by rclpy in this process, and the direct core call. Run:

    .venv/bin/python benchmarks/bench_service.py [--calls 1000] [--uncached-calls 1000]
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_DOMAIN_ID", "91")

import rclpy  # noqa: E402
from rclpy.serialization import deserialize_message, serialize_message  # noqa: E402
from std_msgs.msg import Header  # noqa: E402
from std_srvs.srv import Trigger  # noqa: E402

from biped_gait.core.gait.planner import GaitPlanner, GaitRequest  # noqa: E402
from biped_gait.ros.client import ClientSide, plan_request  # noqa: E402
from biped_gait.ros.conversions import plan_msg, urdf_joints  # noqa: E402
from biped_gait.ros.launch import start_entry, stop_process  # noqa: E402
from biped_gait.ros.planner_node import without_trajectory  # noqa: E402
from biped_gait_interfaces.srv import PlanGait  # noqa: E402

TRIGGER = "/bench_bare_trigger"
BARE_PLAN = "/bench_bare_plan_gait"
TWIN = "_twin"  # a second bare PlanGait process, the same code: how far two alike processes differ
ALPHA = math.radians(23.5)


def bare_server(suffix: str = "") -> None:
    """The yardsticks: a node with a Trigger service and a PlanGait service that answers every
    request with the planner's response to the cached request (made once, before serving),
    spun by ``spin_once`` until killed; their names end with ``suffix`` (a twin process's)."""
    rclpy.init()
    node = rclpy.create_node("bench_bare_services" + suffix)
    planner = GaitPlanner()
    plan = plan_msg(planner.plan(GaitRequest(0.45, 0.45, ALPHA, "normal")), Header(), urdf_joints(planner.model))
    compact = without_trajectory(plan)

    def trigger(_request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        response.success, response.message = True, "ok"
        return response

    def plan_gait(request: PlanGait.Request, response: PlanGait.Response) -> PlanGait.Response:
        response.success, response.message = True, "admissible (found by atlas) (cached)"
        response.plan = compact if request.omit_trajectory else plan
        return response

    node.create_service(Trigger, TRIGGER + suffix, trigger)
    node.create_service(PlanGait, BARE_PLAN + suffix, plan_gait)
    try:
        while rclpy.ok():
            rclpy.spin_once(node, timeout_sec=0.1)
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        pass


def round_trip(side: ClientSide, client, request) -> float:
    """The round-trip time (s) of one call."""
    start = time.perf_counter()
    response = side.call(client, request, timeout=60.0)
    took = time.perf_counter() - start
    assert getattr(response, "success", True), response.message
    return took


def interleaved(side: ClientSide, targets: dict[str, tuple], calls: int) -> dict[str, list[float]]:
    """Round-trip times (s) of ``calls`` calls of each target (name -> (client, request)), one
    of each in turn, so that a change of the machine's load falls on all alike, the order
    rotated each round (a call's place in the round moved its time by up to 15 % in a trial)."""
    times: dict[str, list[float]] = {name: [] for name in targets}
    order = list(targets.items())
    for k in range(calls):
        for name, (client, request) in order[k % len(order):] + order[:k % len(order)]:
            times[name].append(round_trip(side, client, request))
    return times


def summary(times: list[float]) -> str:
    ordered = sorted(times)
    p99 = ordered[min(len(ordered) - 1, math.ceil(0.99 * len(ordered)) - 1)]
    return f"median {1e3 * statistics.median(ordered):7.3f} ms, p99 {1e3 * p99:7.3f} ms ({len(times)} calls)"


def conversion_ms(response: PlanGait.Response, repeat: int = 200) -> tuple[float, float, int]:
    """rclpy's serialization (server) and deserialization (client) of ``response`` (ms) and its
    size (bytes)."""
    data = serialize_message(response)
    start = time.perf_counter()
    for _ in range(repeat):
        serialize_message(response)
    middle = time.perf_counter()
    for _ in range(repeat):
        deserialize_message(data, PlanGait.Response)
    end = time.perf_counter()
    return 1e3 * (middle - start) / repeat, 1e3 * (end - middle) / repeat, len(data)


def first_requests(side: ClientSide, where: Path, fresh: int, calls: int = 10) -> tuple[list[float], list[float]]:
    """Round trips (s) of the first plan request of ``fresh`` freshly started planners (recording
    off), each sent as soon as the service is found and has answered a refused request (so that
    DDS has matched the reply's path too, which a first call otherwise waits for), and of their
    next ``calls`` uncached ones."""
    first, after = [], []
    for k in range(fresh):
        proc = start_entry("biped-gait-planner", ["-r", f"__node:=bench_fresh_{k}", "-p", "record:=false"],
                           log=where / f"fresh_{k}.log", cwd=where)
        try:
            client = side.node.create_client(PlanGait, f"/bench_fresh_{k}/plan_gait")
            side.connect(client)
            refused = side.call(client, PlanGait.Request(step_length=0.45, period=-1.0, arm_amplitude=ALPHA), timeout=60.0)
            assert not refused.success
            requests = [plan_request(step_length=0.45, period=0.45, arm_amplitude=0.35 + 1e-3 * j)
                        for j in range(calls + 1)]
            times = [round_trip(side, client, request) for request in requests]
            first.append(times[0])
            after.extend(times[1:])
            side.node.destroy_client(client)
        finally:
            stop_process(proc)
    return first, after


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=1000)
    parser.add_argument("--uncached-calls", type=int, default=1000)
    parser.add_argument("--fresh", type=int, default=3)
    args = parser.parse_args()
    cached = plan_request(step_length=0.45, period=0.45, arm_amplitude=ALPHA)
    compact = plan_request(step_length=0.45, period=0.45, arm_amplitude=ALPHA, omit_trajectory=True)
    results: dict[str, list[float]] = {}
    alone: dict[str, list[float]] = {}
    quieter: dict[str, list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        where = Path(tmp)
        bare_processes = []
        for suffix in ("", TWIN):
            with open(where / f"bare{suffix}.log", "wb") as log:
                bare_processes.append(subprocess.Popen([sys.executable, __file__, "--bare-server", suffix], stdout=log,
                                                       stderr=log))
        planners = {record: start_entry("biped-gait-planner", ["-r", f"__node:=bench_planner_{record}", "-p",
                                                               f"record:={record}", "-p", f"record_dir:={where}/bags"],
                                        log=where / f"planner_{record}.log", cwd=where)
                    for record in ("true", "false")}
        side = ClientSide("bench_service_client")
        try:
            bare = side.node.create_client(Trigger, TRIGGER)
            bare_plan = side.node.create_client(PlanGait, BARE_PLAN)
            side.connect(bare)
            side.connect(bare_plan)
            twin_plan = side.node.create_client(PlanGait, BARE_PLAN + TWIN)
            side.connect(twin_plan)
            clients = {record: side.node.create_client(PlanGait, f"/bench_planner_{record}/plan_gait")
                       for record in planners}
            for client in clients.values():
                side.connect(client)
            targets = {"bare Trigger service": (bare, Trigger.Request()),
                       "bare PlanGait service, same response": (bare_plan, cached),
                       "bare PlanGait service, no trajectory": (bare_plan, compact),
                       "its twin in another process": (twin_plan, cached),
                       "its twin, no trajectory": (twin_plan, compact),
                       "cached, recording on": (clients["true"], cached),
                       "cached, recording off": (clients["false"], cached),
                       "cached, no trajectory, recording on": (clients["true"], compact),
                       "cached, no trajectory, recording off": (clients["false"], compact)}
            interleaved(side, targets, 20)  # solved once, then cached; warm-up
            results.update(interleaved(side, targets, args.calls))
            alone = {name: [round_trip(side, *targets[name]) for _ in range(args.calls)]
                     for name in ("bare Trigger service", "bare PlanGait service, same response", "cached, recording on",
                                  "bare PlanGait service, no trajectory", "cached, no trajectory, recording on")}
            for k in range(args.uncached_calls):
                for record in ("true", "false"):
                    alpha = 0.30 + 1e-4 * k + (1e-5 if record == "false" else 0.0)
                    name = f"uncached, recording {'on' if record == 'true' else 'off'}"
                    results.setdefault(name, []).append(round_trip(
                        side, clients[record], plan_request(step_length=0.45, period=0.45, arm_amplitude=alpha)))
            stop_process(planners["true"])  # the recording planner's work shares the two cores with the others
            fewer = {name: targets[name] for name in ("bare PlanGait service, same response", "its twin in another process",
                                                      "cached, recording off", "bare PlanGait service, no trajectory",
                                                      "its twin, no trajectory", "cached, no trajectory, recording off")}
            quieter = interleaved(side, fewer, args.calls)
            for proc in planners.values():
                stop_process(proc)
            first, after = first_requests(side, where, args.fresh)
        finally:
            side.close()
            for proc in planners.values():
                stop_process(proc)
            for proc in bare_processes:
                proc.terminate()
                proc.wait()
    solves = []
    planner = GaitPlanner()
    for k in range(20):
        start = time.perf_counter()
        planner.plan(GaitRequest(0.45, 0.45, 0.30 + 1e-4 * k, "normal"))
        solves.append(time.perf_counter() - start)
    plan = plan_msg(planner.plan(GaitRequest(0.45, 0.45, ALPHA, "normal")), Header(), urdf_joints(planner.model))
    conversions = {"whole": conversion_ms(PlanGait.Response(success=True, message="admissible", plan=plan)),
                   "without trajectory": conversion_ms(PlanGait.Response(success=True, message="admissible",
                                                                         plan=without_trajectory(plan)))}
    floors = {"": "bare PlanGait service, same response", "no trajectory": "bare PlanGait service, no trajectory"}

    def ratios(times: dict[str, list[float]], name: str) -> str:
        floor = floors["no trajectory" if "no trajectory" in name else ""]
        ratio = f"{statistics.median(times[name]) / statistics.median(times[floor]):5.2f} x the bare PlanGait"
        if "bare Trigger service" not in times:
            return ratio
        return f"{ratio}, {statistics.median(times[name]) / statistics.median(times['bare Trigger service']):5.2f} x the bare Trigger"

    print("planner service round trip from another process (Fast DDS, localhost), beside bare services:")
    for name, times in results.items():
        print(f"  {name:38s} {summary(times)}  ({ratios(results, name)})")
    print("the recording planner stopped (its recording shares the two cores with the other servers):")
    for name, times in quieter.items():
        print(f"  {name:38s} {summary(times)}  ({ratios(quieter, name)})")
    print("each alone, back to back (each server busy with one client, no other call between):")
    for name, times in alone.items():
        print(f"  {name:38s} {summary(times)}  ({ratios(alone, name)})")
    print(f"freshly started planners ({args.fresh}): first request median {1e3 * statistics.median(first):.2f} ms "
          f"({', '.join(f'{1e3 * t:.1f}' for t in first)}), the next uncached ones {1e3 * statistics.median(after):.2f} ms: "
          f"first / next = {statistics.median(first) / statistics.median(after):.2f}")
    print(f"  direct core call GaitPlanner.plan (uncached): median {1e3 * statistics.median(solves):7.3f} ms")
    for what, (serialize, deserialize, size) in conversions.items():
        print(f"  one PlanGait response, {what} ({size} bytes): rclpy serializes it in {serialize:.3f} ms (server), "
              f"deserializes it in {deserialize:.3f} ms (client)")


if __name__ == "__main__":
    if sys.argv[1:2] == ["--bare-server"]:
        bare_server(*sys.argv[2:])
    else:
        main()
