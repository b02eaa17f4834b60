"""Benchmark: the planner service's round trip from a client in another process.

Starts ``biped-gait-planner`` (recording off), warms its cache with one request, then times
200 calls of that cached request with a client that waits by ``spin_once`` (the fast style), 200 with ``spin_until_future_complete``, and 200 refused requests (a small
reply: the middleware's share without the plan's 91-point trajectory); prints the medians next
to the direct core call (``GaitPlanner.plan``, uncached). Run:

    .venv/bin/python benchmarks/bench_service.py
"""

from __future__ import annotations

import math
import os
import statistics
import tempfile
import time
from pathlib import Path

os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_DOMAIN_ID", "91")

import rclpy  # noqa: E402

from biped_gait.core.planner import GaitPlanner, GaitRequest  # noqa: E402
from biped_gait_interfaces.srv import PlanGait  # noqa: E402

from biped_gait.ros.client import ClientSide  # noqa: E402
from biped_gait.ros.launch import start_entry, stop_process  # noqa: E402

CALLS = 200


def main() -> None:
    request = PlanGait.Request(step_length=0.45, period=0.45, arm_amplitude=math.radians(23.5))
    planner = GaitPlanner()
    core = []
    for _ in range(20):
        start = time.perf_counter()
        planner.plan(GaitRequest(0.45, 0.45, math.radians(23.5), "normal"))
        core.append(time.perf_counter() - start)
    with tempfile.TemporaryDirectory() as tmp:
        proc = start_entry("biped-gait-planner", ["-p", "record:=false"], log=Path(tmp) / "planner.log", cwd=Path(tmp))
        side = ClientSide("bench_client")
        try:
            client = side.node.create_client(PlanGait, "/biped_gait_planner/plan_gait")
            side.connect(client)
            assert side.call(client, request).success
            spin_once, until_complete = [], []
            for _ in range(CALLS):
                start = time.perf_counter()
                response = side.call(client, request)
                spin_once.append(time.perf_counter() - start)
                assert response.message.endswith("(cached)")
            small = PlanGait.Request(step_length=float("nan"))  # refused at once: a small response
            refused = []
            for _ in range(CALLS):
                start = time.perf_counter()
                assert not side.call(client, small).success
                refused.append(time.perf_counter() - start)
            for _ in range(CALLS):
                start = time.perf_counter()
                future = client.call_async(request)
                side.executor.spin_until_future_complete(future, timeout_sec=10.0)
                until_complete.append(time.perf_counter() - start)
        finally:
            side.close()
            stop_process(proc)
    ms = lambda xs: 1e3 * statistics.median(xs)  # noqa: E731
    print(f"planner service, cached request, {CALLS} calls from another process (Fast DDS, localhost):")
    print(f"  round trip, spin_once loop:               median {ms(spin_once):6.3f} ms")
    print(f"  round trip, spin_until_future_complete:   median {ms(until_complete):6.3f} ms")
    print(f"  round trip, refused request (small reply): median {ms(refused):6.3f} ms")
    print(f"  direct core call GaitPlanner.plan (cold): median {ms(core):6.3f} ms")


if __name__ == "__main__":
    rclpy.logging.set_logger_level("bench_client", rclpy.logging.LoggingSeverity.WARN)
    main()
