"""The `sortbot` command: one entry point, sub-commands grouped by workflow in sibling modules."""

from __future__ import annotations

import argparse
import sys

from sortbot.cli import data_commands as data
from sortbot.cli import demo
from sortbot.cli import model_commands as models
from sortbot.cli import sim_commands as sim_cmds


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="sortbot", description="Push, grasp and sort cutlery with a simulated UR3 and an RGB-D camera.")
    sub = p.add_subparsers(dest="command", required=True)

    def scene_args(sp):
        sp.add_argument("--objects", type=int, default=6, help="objects per random scene (3 or 6 cutlery, 10 blocks)")
        sp.add_argument("--object-set", default="cutlery", choices=["cutlery", "blocks"])
        sp.add_argument("--seed", type=int, default=0)

    sim = sub.add_parser("sim", help="the simulated world").add_subparsers(dest="sim_command", required=True)
    sp = sim.add_parser("snapshot", help="RGB, depth and segmentation PNGs (+ labels, scene file) of one scene")
    scene_args(sp)
    sp.add_argument("--scene", help="scene file (JSON/YAML) or shipped scene name instead of a random drop")
    sp.add_argument("--out", required=True)
    sp.add_argument("--overwrite", action="store_true", help="replace files already in --out")
    sp.set_defaults(func=sim_cmds.cmd_snapshot)
    sp = sim.add_parser("run", help="run a policy over seeded episodes and print how well it sorted")
    scene_args(sp)
    sp.add_argument("--policy", default="oracle", choices=["oracle", "random"])
    sp.add_argument("--episodes", type=int, default=20)
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=sim_cmds.cmd_run)
    sp = sim.add_parser("scenes", help="list the shipped hard-case scenes")
    sp.set_defaults(func=sim_cmds.cmd_scenes)

    bench = sub.add_parser("bench", help="benchmarks").add_subparsers(dest="bench_command", required=True)
    sp = bench.add_parser("sim", help="primitive actions/s with one RGB-D observation each (oracle, 6 cutlery)")
    sp.add_argument("--episodes", type=int, default=3)
    sp.add_argument("--objects", type=int, default=6)
    sp.add_argument("--seed", type=int, default=0)
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=sim_cmds.cmd_bench_sim)
    data.add_bench_parser(bench)
    models.add_bench_parser(bench)

    data.add_parsers(sub, scene_args)
    models.add_parsers(sub)

    sp = sub.add_parser("demo", help="the main job on small defaults: snapshot, collect, info, replay, sim bench")
    sp.add_argument("--out", default="outputs/demo")
    sp.add_argument("--seed", type=int, default=0)
    sp.add_argument("--episodes", type=int, default=2)
    sp.set_defaults(func=demo.cmd_demo)
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    for name in ("objects", "episodes", "workers", "actions", "frames", "rounds"):
        value = getattr(args, name, None)
        if isinstance(value, int) and value < 1:  # counts only (replay's --frames is a folder)
            print(f"sortbot: error: --{name} must be at least 1", file=sys.stderr)
            return 2
    try:
        return args.func(args)
    except (ValueError, FileNotFoundError, FileExistsError, ConnectionError) as err:
        print(f"sortbot: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
