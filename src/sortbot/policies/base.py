"""What every policy offers: one Action per Observation. Scripted policies may also read the
privileged state the env hands them; learned ones must not."""

from __future__ import annotations

from typing import Protocol, Sequence

from sortbot.types import Action, Observation


class Policy(Protocol):
    name: str

    def reset(self, seed: int | None = None) -> None:
        """Start a new episode; the seed fixes the policy's randomness."""

    def act(self, obs: Observation, state: Sequence | None = None) -> Action:
        """Choose the next action. `state` is the env's privileged object list, if granted."""
