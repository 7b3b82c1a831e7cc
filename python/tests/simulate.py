"""Noise-free laser-odometry intervals in the contract's model, for exact-recovery tests.

o is the robot's displacement at constant wheel speeds over T, with
v = (r_l phi_l + r_r phi_r)/2 and w = (r_r phi_r - r_l phi_l)/b; the sensor sees
sm = l^-1 (+) o (+) l, l its pose in the robot frame.
"""
import numpy as np


def compose(a, b):
    """a (+) b for SE(2) poses (x, y, theta)."""
    c, s = np.cos(a[2]), np.sin(a[2])
    return np.array([a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2]])


def inverse(a):
    c, s = np.cos(a[2]), np.sin(a[2])
    return np.array([-(c * a[0] + s * a[1]), s * a[0] - c * a[1], -a[2]])


def robot_displacement(r_l, r_r, b, phi_l, phi_r, T):
    v = (r_l * phi_l + r_r * phi_r) / 2
    w = (r_r * phi_r - r_l * phi_l) / b
    theta = w * T
    if abs(theta) < 1e-9:
        return np.array([v * T, 0.0, theta])
    return np.array([v / w * np.sin(theta), v / w * (1 - np.cos(theta)), theta])


def simulate(truth, n=300, seed=7, kinds=(0, 1, 2)):
    """Arrays (T, phi_l, phi_r, sm) of n intervals of the given kinds: 0 straight runs, 1 turns on
    the spot, 2 arcs."""
    r_l, r_r, b, x, y, theta = truth
    mounting = np.array([x, y, theta])
    rng = np.random.default_rng(seed)
    T = rng.uniform(0.5, 1.0, n)
    kind = rng.choice(kinds, n)
    speed = rng.uniform(2.0, 8.0, n) * rng.choice([-1, 1], n)
    turn = rng.uniform(2.0, 8.0, n) * rng.choice([-1, 1], n)
    phi_l = np.where(kind == 0, speed, np.where(kind == 1, -turn, speed - 0.5 * turn))
    phi_r = np.where(kind == 0, speed, np.where(kind == 1, turn, speed + 0.5 * turn))
    sm = np.array([
        compose(compose(inverse(mounting), robot_displacement(r_l, r_r, b, pl, pr, t)), mounting)
        for pl, pr, t in zip(phi_l, phi_r, T)
    ])
    sm[:, 2] = np.arctan2(np.sin(sm[:, 2]), np.cos(sm[:, 2]))
    return T, phi_l, phi_r, sm
