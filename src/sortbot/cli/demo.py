"""`sortbot demo`: the main job on small defaults: a snapshot, a collected dataset (LeRobot + MCAP),
its summary, a replay of one episode, and the sim bench."""

from __future__ import annotations

import argparse
from pathlib import Path

from sortbot.cli import data_commands, sim_commands


def cmd_demo(args) -> int:
    out = Path(args.out)
    print(f"== snapshot of seed {args.seed} -> {out / 'snapshot'}")
    sim_commands.cmd_snapshot(argparse.Namespace(seed=args.seed, out=str(out / "snapshot"), scene=None, objects=6,
                                                 object_set="cutlery", overwrite=True))
    print(f"== collect {args.episodes} oracle episodes of 6 cutlery -> {out / 'data'}")
    data_commands.cmd_collect(argparse.Namespace(
        out=str(out / "data"), episodes=args.episodes, policy="oracle", object_set="cutlery", objects=6, seed=args.seed,
        workers=1, engine="local", ray_address=None, resume=False, overwrite=True, repo_id="local/sortbot-demo",
        max_steps=None))
    print("== datasets info")
    data_commands.cmd_datasets_info(argparse.Namespace(dir=str(out / "data"), json=False))
    print(f"== replay of episode 0 -> {out / 'replay'}")
    data_commands.cmd_replay(argparse.Namespace(file=str(out / "data" / "mcap" / "episode_000000.mcap"),
                                                frames=str(out / "replay"), video=None, json=False))
    print("== sim bench")
    return sim_commands.cmd_bench_sim(argparse.Namespace(episodes=1, objects=6, seed=args.seed, json=False))
