"""The live scene (/twin/scene) with actors: they are not drawn in the static world but where
actors/poses puts them; /actors/poses is served live only when the twin has actors."""

import math

import pytest

from amr_twin.model.actors import Actor
from amr_twin.model.config import load_config
from amr_twin.assembly.twin import Twin, TwinOptions

pytest.importorskip("foxglove")

CFG = load_config()


def _decoded(update):
    """A foxglove SceneUpdate decoded with protobuf from its own schema (its fields readable)."""
    pytest.importorskip("google.protobuf")
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    schema = update.get_schema()
    pool = descriptor_pool.DescriptorPool()
    for f in descriptor_pb2.FileDescriptorSet.FromString(bytes(schema.data)).file:
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name)).FromString(
        bytes(update.encode())
    )


def test_actors_are_drawn_at_their_poses_not_in_the_static_world():
    from amr_twin.live.foxglove import live_topics
    from amr_twin.live.scene import SceneBuilder

    walker = Actor("person", ((-3.0, 2.0), (-3.0, -2.0)), 1.0)
    twin = Twin(CFG, TwinOptions(start_xy_yaw=(-6.0, 0.0, 0.0), actors=(walker,)))
    scene = SceneBuilder(twin.observables.model, twin.observables.named)
    world = _decoded(scene.static_update()).entities[0]
    assert (
        world.id == "world" and len(world.cylinders) == 0
    )  # the warehouse has no cylinder: no legs
    (entity,) = _decoded(scene.actors_update(5, [(1.0, 0.5, math.pi / 2)])).entities
    assert entity.id == "actors" and entity.frame_id == "odom" and len(entity.cylinders) == 2
    legs = sorted((c.pose.position.x, c.pose.position.y) for c in entity.cylinders)
    half = CFG.actors.person.leg_spacing_m / 2  # across its heading (+y): along x
    # odom is base_link at t = 0, (-6, 0) facing +x: the world point (x, y) is (x + 6, y) in odom
    assert legs[0] == pytest.approx((7.0 - half, 0.5), abs=1e-3) and legs[1] == pytest.approx(
        (7.0 + half, 0.5), abs=1e-3
    )
    assert all(c.size.z == pytest.approx(CFG.actors.person.leg_length_m) for c in entity.cylinders)
    assert "/actors/poses" in live_topics(twin)
    assert "/actors/poses" not in live_topics(Twin(CFG, TwinOptions(start_xy_yaw=(-6.0, 0.0, 0.0))))
