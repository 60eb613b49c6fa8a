"""The master's watch stops when closed, even in the middle of registering the node again with a
slow master: it makes no call after the one under way, and its thread is gone when ``close``
returns (before the twin shuts rospy down and exits)."""

import threading
import time
import types
import xmlrpc.server

from conftest import needs_ros1

pytestmark = needs_ros1


class SlowMaster:
    """An XML-RPC master whose pid changes after the first look (a restart) and whose ``setParam``
    takes ``slow_s``; counts the ``setParam`` calls."""

    def __init__(self, slow_s: float):
        self.looks, self.set_params, self.slow_s = 0, 0, slow_s
        self.server = xmlrpc.server.SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False)
        self.server.register_function(self.getPid, "getPid")
        self.server.register_function(self.setParam, "setParam")
        self.uri = f"http://127.0.0.1:{self.server.server_address[1]}"
        threading.Thread(target=self.server.serve_forever, daemon=True).start()

    def getPid(self, _caller):  # noqa: N802 - the master API's name
        self.looks += 1
        return [1, "", 100 if self.looks == 1 else 200]

    def setParam(self, _caller, _key, _value):  # noqa: N802
        self.set_params += 1
        time.sleep(self.slow_s)
        return [1, "", 0]

    def close(self):
        self.server.shutdown()
        self.server.server_close()


def test_close_during_a_registration_waits_for_one_call_and_makes_no_more():
    from amr_twin.ros1.installation import import_rospy
    from amr_twin.ros1.master_watch import MasterWatch

    import_rospy()  # the watch's registration reads rospy's lists (after the parameters)
    master = SlowMaster(slow_s=0.8)
    rospy = types.SimpleNamespace(
        get_name=lambda: "/test_watch",
        core=types.SimpleNamespace(get_node_uri=lambda: "http://127.0.0.1:9/"),
    )
    params = {f"/p{i}": i for i in range(6)}  # six slow calls: 4.8 s
    said = []
    try:
        watch = MasterWatch(master.uri, rospy, params, said.append, period_s=0.05)
        deadline = time.monotonic() + 30
        while master.set_params == 0:  # the restart seen: the first parameter under way
            assert time.monotonic() < deadline, "no registration"
            time.sleep(0.01)
        start = time.monotonic()
        watch.close()
        took = time.monotonic() - start
        alive = watch._thread.is_alive()
        calls = master.set_params
        time.sleep(1.0)  # a thread left running would go on calling
    finally:
        master.close()
    assert not alive and took < 2.5, (alive, took)
    assert calls == master.set_params == 1, (calls, master.set_params)
    assert not any("registered again" in line for line in said), said
