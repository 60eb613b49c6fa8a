"""``--actor`` and ``--actors-random`` of ``amr-twin run`` (and of its goto and navigation
missions): the people and pallet jacks that walk the world (amr_twin/model/actors.py), checked in
one line each."""

from __future__ import annotations

import math

from amr_twin.cli.common import _guard, fail
from amr_twin.cli.run_options import RunOptions


MAX_ACTORS = 50
"""Most actors in one run (each costs a few microseconds a grid instant and a mocap body)."""


def checked_actors(opts: RunOptions, mission_actors: tuple, cfg, start) -> tuple:
    """The mission's actors, ``--actor``'s and ``--actors-random``'s, in that order; a bad one
    refused in one line (their paths are checked against the world when it is built)."""
    from amr_twin.model.actors import Actor, ActorError, check_speeds

    try:
        actors = list(mission_actors) + [Actor.parse(text, cfg) for text in opts.actor]
        if opts.actors_random is not None:
            count, _, flag = opts.actors_random.partition("/")
            if (
                not count.isdigit()
                or not 1 <= int(count) <= MAX_ACTORS
                or (flag and not flag.startswith("stop="))
            ):
                fail(
                    f"--actors-random {opts.actors_random!r}: expected N[/stop=M] with N in "
                    f"1..{MAX_ACTORS}"
                )
            stop = _stop_distance(opts.actors_random, flag[5:]) if flag else 0.0
            actors += list(_guard(lambda: _random_actors(cfg, opts, int(count), start, stop)))
        check_speeds(tuple(actors), cfg)
    except (ActorError, ValueError) as exc:
        fail(str(exc))
    if len(actors) > MAX_ACTORS:
        fail(f"--actor: {len(actors)} actors, at most {MAX_ACTORS}")
    return tuple(actors)


def _stop_distance(given: str, text: str) -> float:
    """``--actors-random``'s ``/stop=M``, m; a one-line refusal naming the option (was Python's
    "could not convert string to float")."""
    from amr_twin.model.actors import MAX_STOP_M

    try:
        stop_m = float(text)
    except ValueError:
        stop_m = math.nan
    if not (math.isfinite(stop_m) and 0 <= stop_m <= MAX_STOP_M):
        fail(f"--actors-random {given!r}: /stop=M takes a distance M in [0, {MAX_STOP_M:g}] m")
    return stop_m


def _random_actors(cfg, opts: RunOptions, count: int, start, stop_m: float) -> tuple:
    from amr_twin.model.actor_space import random_actors
    from amr_twin.model.world_spec import world_model
    from amr_twin.model.worlds import default_start

    x, y, _yaw = start if start is not None else default_start(opts.world)
    return random_actors(
        world_model(cfg, opts.world), count, opts.seed, cfg, (x, y), stop_within_m=stop_m
    )
