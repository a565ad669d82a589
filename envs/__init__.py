"""roller-gym: Gymnasium environments on the instant-center dynamics of a driven roller.

``import envs`` registers the tasks with Gymnasium. The physics (no Gymnasium) is in
:mod:`envs.physics`.
"""

from envs.physics import PRESETS, Scene, preset

__all__ = ["PRESETS", "Scene", "preset"]
