"""`sortbot collect`, `datasets info|merge|push|export-yolo`, `replay`, `bench collect`."""

from __future__ import annotations

import json
import sys
from pathlib import Path


def _print_json(data) -> None:
    print(json.dumps(data, indent=1, default=str))


def cmd_collect(args) -> int:
    from tqdm import tqdm

    from sortbot.collect.runner import CollectRequest, collect

    from sortbot.config import EnvConfig

    env_config = EnvConfig()
    if args.max_steps is not None:
        env_config.outcome.max_steps = args.max_steps
    req = CollectRequest(out=Path(args.out), episodes=args.episodes, policy=args.policy, object_set=args.object_set,
                         objects=args.objects, seed=args.seed, workers=args.workers, engine=args.engine,
                         ray_address=args.ray_address, resume=args.resume, overwrite=args.overwrite,
                         repo_id=args.repo_id, env_config=env_config)
    # delay: a refused --out fails before any bar is drawn
    bar = tqdm(total=args.episodes, desc=f"collect {args.policy}", unit="ep", file=sys.stderr, delay=2)

    def progress(done: int, total: int, info: dict) -> None:
        bar.n = done
        bar.set_postfix(frames=info["frames"], last=info["end"])
        bar.refresh()

    try:
        result = collect(req, progress=progress)
    finally:
        bar.close()
    if result.first_episode >= args.episodes:
        print(f"nothing to do: {req.out} already holds {result.episodes} episodes")
        return 0
    rate = result.frames / result.wall_s if result.wall_s else 0.0
    print(f"episodes {result.first_episode}..{result.episodes - 1} -> {req.out / 'lerobot'} (LeRobot v3) and "
          f"{req.out / 'mcap'} (MCAP): {result.frames} frames in {result.wall_s:.1f} s ({rate:.2f} frames/s); "
          f"sorted {result.sorted_correctly}/{result.objects} objects")
    return 0


def cmd_datasets_info(args) -> int:
    from sortbot.datasets.summary import dataset_summary

    info = dataset_summary(Path(args.dir))
    if args.json:
        _print_json(info)
        return 0
    o = info["outcomes"]
    lines = [
        ("dataset", f"{info['root']} ({info['repo_id']})"),
        ("collected by", f"{info['policy']} on {info['objects_per_scene']} {info['object_set']} per scene"),
        ("episodes / frames", f"{info['episodes']} / {info['frames']}"),
        ("grasps", f"{o['grasps']}: {o['grasp_success']} held, {o['well_placed']} well placed"),
        ("pushes", f"{o['pushes']}: {o['push_moved']} moved something, {o['change_detected']} change-detected (VPG)"),
        ("unreachable", str(o["unreachable"])),
        ("episode ends", ", ".join(f"{k}: {v}" for k, v in info["end_reasons"].items())),
        ("sorted correctly", f"{info['sorted_correctly']}/{info['objects']} objects"),
        ("classes in scenes", ", ".join(f"{k}: {v}" for k, v in info["class_balance_scenes"].items())),
        ("classes in labels", ", ".join(f"{k}: {v}" for k, v in info["class_balance_labels"].items())),
        ("size on disk", f"{info['size_bytes'] / 2**20:.1f} MiB ({info['bytes_per_frame'] / 1024:.0f} KiB/frame)"),
    ]
    if info["staged_episodes"]:
        lines.append(("not folded in yet", f"{info['staged_episodes']} finished episodes in {info['staging_dir']} "
                                           "(a run was stopped early): `sortbot collect ... --resume` folds them in"))
    for key, value in lines:
        print(f"{key:20s} {value}")
    return 0


def cmd_datasets_merge(args) -> int:
    from sortbot.datasets.merge import merge_datasets

    root = merge_datasets([Path(p) for p in args.sources], Path(args.out), overwrite=args.overwrite, repo_id=args.repo_id)
    print(f"merged {len(args.sources)} datasets -> {root}")
    return cmd_datasets_info(type(args)(dir=str(root), json=False))


def cmd_datasets_push(args) -> int:
    from sortbot.datasets.hub import push_dataset

    files = push_dataset(Path(args.dir), args.repo_id, private=args.private, dry_run=args.dry_run)
    total = sum(size for _, size in files)
    if args.dry_run:
        for name, size in files:
            print(f"{size:>12d}  {name}")
        print(f"dry run: would upload {len(files)} files, {total / 2**20:.1f} MiB to {args.repo_id}")
    else:
        print(f"pushed {len(files)} files, {total / 2**20:.1f} MiB to https://huggingface.co/datasets/{args.repo_id}")
    return 0


def cmd_datasets_export_yolo(args) -> int:
    from tqdm import tqdm

    from sortbot.datasets.yolo_export import YoloExportConfig, export_yolo

    bar = tqdm(desc="export-yolo", unit="frame", file=sys.stderr)

    def progress(done: int, total: int) -> None:
        bar.total = total
        bar.update(done - bar.n)

    config = YoloExportConfig(val_fraction=args.val_fraction, label_sorted=args.label_sorted)
    if args.no_crop:
        config.crop = None
    data_yaml = export_yolo(Path(args.dir), Path(args.out), config, overwrite=args.overwrite, progress=progress)
    bar.close()
    print(data_yaml)
    return 0


def cmd_replay(args) -> int:
    from sortbot.eval.replay import draw_frames, load, step_rows, summary, write_frames, write_video

    log = load(Path(args.file), images=bool(args.frames or args.video))
    info = summary(log)
    if args.json:
        _print_json({**info, "steps": step_rows(log)})
    else:
        from rich.console import Console
        from rich.table import Table

        table = Table(title=f"{log.path.name}: seed {info['seed']}, policy {info['policy']}")
        for col in ("step", "action", "at (x, y, z) m", "angle", "result", "reward", "sim s", "wall s"):
            table.add_column(col)
        for r in step_rows(log):
            x, y, z = r["position"]
            table.add_row(str(r["step"]), r["primitive"], f"{x:.3f}, {y:.3f}, {z:.3f}", f"{r['angle']:.2f}", r["result"],
                          "" if r["reward"] is None else f"{r['reward']:.1f}", "" if r["sim_s"] is None else f"{r['sim_s']:.2f}",
                          "" if r["wall_s"] is None else f"{r['wall_s']:.2f}")
        console = Console()
        console.print(table)
        console.print(f"{info['actions']} actions: {info['grasp_success']}/{info['grasps']} grasps held, {info['well_placed']} well placed, "
                      f"{info['push_moved']}/{info['pushes']} pushes moved something; sim {info['sim_time_s']:.1f} s, "
                      f"wall {info['wall_time_s']:.1f} s; end: {info['end_reason']}")
    images = draw_frames(log) if (args.frames or args.video) else []
    if args.frames:
        paths = write_frames(images, Path(args.frames))
        print(f"{len(paths) - 1} frames and a contact sheet -> {args.frames}")
    if args.video:
        print(f"video -> {write_video(images, Path(args.video))}")
    if log.error:
        print(f"sortbot: error: {args.file} is damaged: {log.error}; shown: the {len(log.actions)} actions read before it",
              file=sys.stderr)
        return 1
    return 0


def cmd_bench_collect(args) -> int:
    from tqdm import tqdm

    from sortbot.collect.bench import bench_collect, soak

    if args.soak:
        bar = tqdm(total=args.actions, desc="soak", unit="action", file=sys.stderr, disable=args.json)
        result = soak(actions=args.actions, objects=args.objects, seed=args.seed, policy=args.policy,
                      workers=args.workers, progress=lambda done, total, info: bar.update(done - bar.n),
                      on_sample=lambda sample: bar.write(json.dumps(sample), file=sys.stderr))
        bar.close()
    else:
        bar = tqdm(desc="bench collect", unit="ep", file=sys.stderr, disable=args.json)
        result = bench_collect(episodes=args.episodes, objects=args.objects, seed=args.seed, policy=args.policy,
                               progress=lambda done, total, info: bar.update(1))
        bar.close()
    if args.json:
        _print_json(result)
    else:
        for key, value in result.items():
            print(f"{key:36s} {json.dumps(value, default=str) if isinstance(value, (dict, list)) else value}")
    return 0


def add_parsers(sub, scene_args) -> None:
    from sortbot.collect.engines import ENGINES
    from sortbot.datasets.lerobot_store import DEFAULT_REPO_ID
    from sortbot.policies import POLICIES

    sp = sub.add_parser("collect", help="run a policy over seeded episodes into a LeRobot v3 dataset + MCAP logs")
    scene_args(sp)
    sp.add_argument("--policy", default="oracle", choices=list(POLICIES))
    sp.add_argument("--episodes", type=int, default=10, help="episodes in the dataset in total (with --resume: up to this many)")
    sp.add_argument("--out", required=True, help="folder for lerobot/ and mcap/")
    sp.add_argument("--workers", type=int, default=1, help="episodes collected in parallel")
    sp.add_argument("--engine", default="local", choices=list(ENGINES), help="local processes or Ray actors")
    sp.add_argument("--ray-address", help="Ray cluster address (from `ray start --head`); default: a local instance")
    sp.add_argument("--max-steps", type=int, help="step budget per episode (default: OutcomeConfig.max_steps)")
    sp.add_argument("--resume", action="store_true", help="continue after the last finished episode in --out")
    sp.add_argument("--overwrite", action="store_true", help="replace what --out holds")
    sp.add_argument("--repo-id", default=DEFAULT_REPO_ID, help="LeRobot repo id stored in the dataset")
    sp.set_defaults(func=cmd_collect)

    ds = sub.add_parser("datasets", help="inspect, merge, share and export collected datasets").add_subparsers(dest="datasets_command", required=True)
    sp = ds.add_parser("info", help="episodes, frames, outcomes, class balance, size on disk")
    sp.add_argument("dir")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=cmd_datasets_info)
    sp = ds.add_parser("merge", help="merge datasets with lerobot's aggregation")
    sp.add_argument("sources", nargs="+")
    sp.add_argument("--out", required=True)
    sp.add_argument("--repo-id")
    sp.add_argument("--overwrite", action="store_true")
    sp.set_defaults(func=cmd_datasets_merge)
    sp = ds.add_parser("push", help="upload to the Hugging Face Hub with lerobot's push_to_hub")
    sp.add_argument("dir")
    sp.add_argument("--repo-id", required=True, help="ORG/NAME on the Hub")
    sp.add_argument("--private", action="store_true")
    sp.add_argument("--dry-run", action="store_true", help="list what would be uploaded; no network")
    sp.set_defaults(func=cmd_datasets_push)
    sp = ds.add_parser("export-yolo", help="RGB frames + labels as a YOLO detection set, split by episode")
    sp.add_argument("dir")
    sp.add_argument("--out", required=True)
    sp.add_argument("--val-fraction", type=float, default=0.2)
    sp.add_argument("--no-crop", action="store_true", help="whole frames (default: cut to the pick area, labels clipped)")
    sp.add_argument("--label-sorted", action="store_true",
                    help="also label cutlery lying in a bin (default: sorted cutlery is no target, so unlabelled)")
    sp.add_argument("--overwrite", action="store_true")
    sp.set_defaults(func=cmd_datasets_export_yolo)

    sp = sub.add_parser("replay", help="summarise an episode MCAP; draw its frames, contact sheet, video")
    sp.add_argument("file")
    sp.add_argument("--frames", help="folder for PNG frames and contact_sheet.png")
    sp.add_argument("--video", help="MP4 file to write")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=cmd_replay)


def add_bench_parser(bench) -> None:
    from sortbot.policies import POLICIES

    sp = bench.add_parser("collect", help="frames/s and bytes/frame written, 2 workers vs 1; --soak for memory")
    sp.add_argument("--episodes", type=int, default=2)
    sp.add_argument("--objects", type=int, default=6)
    sp.add_argument("--seed", type=int, default=0)
    sp.add_argument("--policy", default="oracle", choices=list(POLICIES))
    sp.add_argument("--soak", action="store_true", help="run --actions actions and report memory at start and end")
    sp.add_argument("--actions", type=int, default=10_000)
    sp.add_argument("--workers", type=int, default=1, help="workers for --soak")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=cmd_bench_collect)
