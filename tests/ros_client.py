"""A test client for a sim_node running in its own process: its own rclpy context on a domain of
its own, a background executor, and blocking helpers with timeouts for services, parameters and
topics."""
import collections
import signal
import subprocess
import threading
import time

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter, parameter_value_to_python
from rclpy.parameter_client import AsyncParameterClient
from rclpy.qos import DurabilityPolicy, QoSProfile
from rclpy.signals import SignalHandlerOptions


class Client:
    def __init__(self, domain_id: int, target: str = "/sim_node"):
        self.target = target
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain_id, signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node("test_client", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self.executor.spin, daemon=True)
        self._thread.start()
        self.params = AsyncParameterClient(self.node, target)
        self.messages = collections.defaultdict(list)
        self.arrivals = collections.defaultdict(list)  # time.monotonic() of each message's arrival
        self._lock = threading.Lock()
        self._clients = {}

    def close(self):
        # the spinning thread ends before its node goes: destroyed under a spinning executor, the node
        # once left it busy-waiting on the GIL, and a test's next wait for its node process never woke
        self.executor.shutdown(timeout_sec=10.0)
        self._thread.join(timeout=10.0)
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)

    @staticmethod
    def _wait(future, timeout):
        deadline = time.monotonic() + timeout
        while not future.done():
            if time.monotonic() > deadline:
                raise TimeoutError("no answer")
            time.sleep(0.005)
        return future.result()

    # -- topics ---------------------------------------------------------------------------------
    def subscribe(self, topic, msg_type, depth=10, latched=False):
        """Keep what ``topic`` brings; ``latched``: ask for what the publisher kept (transient local),
        as RViz does for a map."""
        def keep(msg):
            with self._lock:
                self.messages[topic].append(msg)
                self.arrivals[topic].append(time.monotonic())

        qos = QoSProfile(depth=depth, durability=DurabilityPolicy.TRANSIENT_LOCAL if latched
                         else DurabilityPolicy.VOLATILE)
        self.node.create_subscription(msg_type, topic, keep, qos)

    def received(self, topic) -> list:
        with self._lock:
            return list(self.messages[topic])

    def clear(self, topic):
        with self._lock:
            self.messages[topic].clear()
            self.arrivals[topic].clear()

    def wait_for(self, topic, predicate=bool, timeout=60.0) -> list:
        """The messages of ``topic`` once ``predicate(messages)`` holds."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            msgs = self.received(topic)
            if predicate(msgs):
                return msgs
            time.sleep(0.02)
        raise TimeoutError(f"{topic}: condition not met in {timeout} s ({len(self.received(topic))} messages)")

    # -- services and parameters ----------------------------------------------------------------
    def call(self, service, srv_type, timeout=60.0, **fields):
        client = self._clients.get(service)
        if client is None:
            client = self._clients[service] = self.node.create_client(srv_type, f"{self.target}/{service}")
            assert client.wait_for_service(timeout_sec=30.0), service
        return self._wait(client.call_async(srv_type.Request(**fields)), timeout)

    def set(self, **values):
        """Set parameters one by one; the SetParametersResult of each."""
        assert self.params.wait_for_services(timeout_sec=30.0)
        params = [Parameter(name, value=value) for name, value in values.items()]
        return self._wait(self.params.set_parameters(params), 30.0).results

    def set_together(self, **values):
        """Set parameters atomically; one SetParametersResult."""
        assert self.params.wait_for_services(timeout_sec=30.0)
        params = [Parameter(name, value=value) for name, value in values.items()]
        return self._wait(self.params.set_parameters_atomically(params), 30.0).result

    def get(self, *names) -> dict:
        assert self.params.wait_for_services(timeout_sec=30.0)
        values = self._wait(self.params.get_parameters(list(names)), 30.0).values
        return {name: parameter_value_to_python(v) for name, v in zip(names, values)}


def stop(proc, timeout=30.0):
    """A node process stopped as ros2 run's Ctrl-C would (SIGINT), killed after ``timeout`` s."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
