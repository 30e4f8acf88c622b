"""Decisions: scripted oracle, random policy (learned ones come with the training issue)."""

from sortbot.policies.oracle import OraclePolicy
from sortbot.policies.random_policy import RandomPolicy

POLICIES = {"oracle": OraclePolicy, "random": RandomPolicy}


def make_policy(name: str, gripper=None, workspace=None):
    if name == "oracle":
        return OraclePolicy(gripper=gripper, workspace=workspace)
    if name == "random":
        return RandomPolicy(workspace=workspace)
    raise ValueError(f"unknown policy {name!r}: use one of {', '.join(POLICIES)}")
