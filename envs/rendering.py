"""Drawing a roller scene with pygame (imported only when an environment renders).

The picture: the fixed surface (the cylinder's wall, the floor or the drum), the roller
with a spoke that shows its rotation, the mass center C (black), the instant center I
(red), the target contact point (green, tasks with a target) and the torque (an orange
arc around the axle, its length proportional to τ/max_torque, its arrow the sense).
"""

from __future__ import annotations

import math

import numpy as np
from roller_gym.physics import Scene, kinematics

__all__ = ["Renderer"]

SIZE = 500  # window side [px]
#: How far off the picture [px] a point is drawn: further ones are drawn there (unseen), since
#: pygame's drawing takes 16-bit coordinates (a target hundreds of radians along a floor).
_OFF = 8 * SIZE
_WALL = (60, 60, 70)
_ROLLER = (180, 200, 230)
_RIM = (40, 70, 140)
_MASS = (0, 0, 0)
_CONTACT = (220, 30, 30)
_TARGET = (30, 160, 60)
_TORQUE = (240, 140, 0)
_BACKGROUND = (255, 255, 255)


class Renderer:
    """Draws frames of a scene; ``mode`` is ``"human"`` (a window) or ``"rgb_array"``."""

    def __init__(self, mode: str, fps: int) -> None:
        try:
            import pygame
            from pygame import gfxdraw
        except ImportError as exc:  # pragma: no cover - depends on the install
            from roller_gym.extras import missing

            raise missing("pygame", "render", "rendering") from exc
        self.pg, self.gfx = pygame, gfxdraw
        self.mode, self.fps = mode, fps
        if mode == "human":
            pygame.display.init()
            self.screen = pygame.display.set_mode((SIZE, SIZE))
            pygame.display.set_caption("roller-gym")
        else:
            self.screen = None
        self.surface = pygame.Surface((SIZE, SIZE))
        self.clock = pygame.time.Clock()

    def _view(self, scene: Scene, o1x: float) -> tuple[float, float, float]:
        """(center x [m], center y [m], pixels per metre) of the picture."""
        r, R = float(scene.r), float(scene.R)
        if math.isinf(R):
            return o1x, 2.0 * r, SIZE / (12.0 * r)
        half = 1.15 * abs(R) if R > 0 else abs(R) + 3.0 * r
        return 0.0, R if R > 0 else 0.5 * (R + 2.0 * r), SIZE / (2.0 * half)

    def draw(self, scene: Scene, phi: float, target: float, torque: float, max_torque: float,
             show_target: bool) -> np.ndarray | None:
        pg, gfx, surf = self.pg, self.gfx, self.surface
        k = kinematics(scene, phi)
        o1x, o1y = (float(v) for v in k.o1)
        cx0, cy0, scale = self._view(scene, o1x)

        def px(x: float, y: float) -> tuple[int, int]:
            return (int(min(max(SIZE / 2 + (x - cx0) * scale, -_OFF), _OFF)),
                    int(min(max(SIZE / 2 - (y - cy0) * scale, -_OFF), _OFF)))

        surf.fill(_BACKGROUND)
        r, R = float(scene.r), float(scene.R)
        if math.isinf(R):
            y = px(0.0, 0.0)[1]
            pg.draw.line(surf, _WALL, (0, y), (SIZE, y), 3)
            for x in range(-SIZE, 2 * SIZE, 25):  # hatching that moves with the floor
                x0 = px(math.floor((cx0 * scale) / 25) * 25 / scale, 0)[0] + x % 25
                pg.draw.line(surf, _WALL, (x0, y), (x0 - 10, y + 10), 1)
        elif R > 0:
            center, radius = px(0.0, R), int(R * scale)
            gfx.aacircle(surf, *center, radius, _WALL)
            pg.draw.circle(surf, _WALL, center, radius, 3)
        else:
            center, radius = px(0.0, R), int(-R * scale)
            gfx.filled_circle(surf, *center, radius, (200, 200, 205))
            gfx.aacircle(surf, *center, radius, _WALL)

        o1 = px(o1x, o1y)
        rr = max(int(r * scale), 2)
        gfx.filled_circle(surf, *o1, rr, _ROLLER)
        gfx.aacircle(surf, *o1, rr, _RIM)
        for angle in (0.0, 0.5 * math.pi):  # two spokes fixed in the roller
            end = px(o1x - r * math.sin(phi + angle), o1y - r * math.cos(phi + angle))
            pg.draw.aaline(surf, _RIM, o1, end)
        if show_target:
            t = kinematics(scene, target)
            gfx.filled_circle(surf, *px(*(float(v) for v in t.i)), max(rr // 6, 3), _TARGET)
        gfx.filled_circle(surf, *px(*(float(v) for v in k.c)), max(rr // 8, 3), _MASS)
        gfx.filled_circle(surf, *px(*(float(v) for v in k.i)), max(rr // 10, 3), _CONTACT)

        share = max(-1.0, min(1.0, torque / max_torque)) if max_torque > 0 else 0.0
        if abs(share) > 1e-3:
            radius = 0.6 * r
            start = 0.5 * math.pi
            angles = np.linspace(start, start - share * 1.5 * math.pi, 24)  # clockwise: φ's sense
            points = [px(o1x + radius * math.cos(a), o1y + radius * math.sin(a)) for a in angles]
            pg.draw.lines(surf, _TORQUE, False, points, 3)
            a = angles[-1]
            tip = np.array(points[-1], dtype=float)
            direction = np.array([math.sin(a), math.cos(a)]) * (1 if share > 0 else -1)
            normal = np.array([-direction[1], direction[0]])
            head = [tip + 8 * direction, tip + 5 * normal, tip - 5 * normal]
            pg.draw.polygon(surf, _TORQUE, [tuple(map(int, p)) for p in head])

        if self.mode == "human":
            assert self.screen is not None
            pg.event.pump()
            self.screen.blit(surf, (0, 0))
            pg.display.flip()
            self.clock.tick(self.fps)
            return None
        return np.transpose(np.array(pg.surfarray.pixels3d(surf)), axes=(1, 0, 2)).copy()

    def close(self) -> None:
        if self.mode == "human":
            self.pg.display.quit()
