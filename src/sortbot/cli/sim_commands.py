"""`sortbot sim snapshot|run|scenes`, `bench sim` and `demo`."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def _env_config(args):
    from sortbot.config import EnvConfig

    cfg = EnvConfig()
    cfg.scene.num_objects = args.objects
    cfg.scene.object_set = args.object_set
    return cfg


def _check_out(out: Path, names: list[str], overwrite: bool) -> None:
    clash = [n for n in names if (out / n).exists()]
    if clash and not overwrite:
        raise FileExistsError(f"{out} already holds {', '.join(clash)}: choose another --out or pass --overwrite")
    out.mkdir(parents=True, exist_ok=True)


def cmd_snapshot(args) -> int:
    from sortbot.sim.env import SortingEnv
    from sortbot.sim.scene_file import save_scene
    from sortbot.sim.snapshot import write_snapshot

    out = Path(args.out)
    _check_out(out, ["rgb.png", "depth.png", "segmentation.png", "labels.json", "scene.json"], args.overwrite)
    with SortingEnv(_env_config(args)) as env:
        obs = env.reset(seed=args.seed, scene=args.scene)
        paths = write_snapshot(obs, env.instance_map(), out)
        paths.append(save_scene(env.current_scene(), out / "scene.json"))
    for p in paths:
        print(p)
    print(f"{len(obs.labels)} labelled objects: " + ", ".join(f"{l.instance_id}:{l.cls}" for l in obs.labels))
    return 0


def cmd_run(args) -> int:
    from tqdm import tqdm

    from sortbot.eval.rollout import RolloutSummary, run_episode
    from sortbot.policies import make_policy
    from sortbot.sim.env import SortingEnv

    cfg = _env_config(args)
    policy = make_policy(args.policy, cfg.gripper, cfg.workspace)
    summary = RolloutSummary()
    with SortingEnv(cfg) as env:
        for k in tqdm(range(args.episodes), desc=f"{args.policy} episodes", unit="ep", disable=args.json):
            summary.episodes.append(run_episode(env, policy, args.seed + k))
    result = summary.as_dict()
    if args.json:
        print(json.dumps(result, indent=1))
        return 0
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"{args.policy}: {args.episodes} episodes, {args.objects} {args.object_set}, seeds {args.seed}..{args.seed + args.episodes - 1}")
    for col in ("seed", "sorted", "actions", "grasps ok", "pushes moved", "end"):
        table.add_column(col)
    for e in summary.episodes:
        table.add_row(str(e.seed), f"{e.sorted_correctly}/{e.objects}", str(e.actions), f"{e.grasp_successes}/{e.grasps}",
                      f"{e.pushes_moved}/{e.pushes}", str(e.end_reason))
    console = Console()
    console.print(table)
    console.print(
        f"objects sorted into the right bin: {result['sorted_correctly']}/{result['objects']} = {100 * result['sorted_fraction']:.1f} %  |  "
        f"grasp success {100 * result['grasp_success']:.1f} %  |  well placed / grasps {100 * result['well_placed_of_grasps']:.1f} %  |  "
        f"push moved {100 * result['push_moved']:.1f} % (change detected {100 * result['push_change_detected']:.1f} %)"
    )
    return 0


def cmd_scenes(args) -> int:
    from sortbot.sim.scene_file import load_scene, shipped_scenes

    for name in shipped_scenes():
        print(f"{name:24s} {load_scene(name).description}")
    return 0


def cmd_bench_sim(args) -> int:
    from tqdm import tqdm

    from sortbot.eval.sim_bench import bench_sim

    bar = tqdm(total=args.episodes, desc="bench sim", unit="ep", disable=args.json, file=sys.stderr)
    result = bench_sim(episodes=args.episodes, objects=args.objects, seed=args.seed, progress=lambda k, n: bar.update(1))
    bar.close()
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        for k, v in result.items():
            print(f"{k:40s} {v:.3f}" if isinstance(v, float) else f"{k:40s} {v}")
    return 0
