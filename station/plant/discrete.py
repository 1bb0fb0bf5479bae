"""Sampled SFLR plant (exact zero-order hold) and the rig's sensors.

Timing (ARCHITECTURE.md): at tick k the sensors see x_k; the command v[k] is held by
the DAC during the tick, x_{k+1} = Ad x_k + Bd v[k] (exact ZOH, never a per-sample ODE
solve: DESIGN.md "Time stepping").
"""

from __future__ import annotations

import numpy as np

# scipy.linalg / scipy.signal / scipy.optimize / python-control are imported where used:
# they cost seconds, and a run's first tick does not need them (start-up time).

from station.rig import DT
from station.plant.fem import state_matrices
from station.plant.parameters import Params, load_params
from station.rounding import sensor_count


class DiscretePlant:
    """The FEM plant sampled with an exact zero-order hold.

    Parameters
    ----------
    params : Params, optional
        Parameter set; default ``load_params("tmm-fit")``.
    n_elements : int, default 4
        Beam element count, 1..100.
    dt : float, default 0.002
        Sample time, s.

    Attributes
    ----------
    Ad : ndarray, shape (n_x, n_x)
        State transition over one sample (scipy.signal.cont2discrete, method "zoh").
    Bd : ndarray, shape (n_x,)
        State change per DAC count held for one sample.
    Cd : ndarray, shape (2, n_x)
        Outputs [theta (encoder counts), a (accelerometer counts)]; D = 0.
    x : ndarray, shape (n_x,)
        Current state in the scaled modal coordinates of `fem.state_matrices`
        (zero after `reset`: the plant at rest at the origin).
    params, n_elements, dt
        As given.
    """

    def __init__(self, params: Params | None = None, n_elements: int = 4, dt: float = DT):
        self.params = load_params() if params is None else params
        self.n_elements = n_elements
        self.dt = float(dt)
        A, B, C = state_matrices(self.params, n_elements)
        import scipy.signal  # lazy: start-up time (scipy.signal)
        Ad, Bd, Cd, _, _ = scipy.signal.cont2discrete((A, B, C, np.zeros((2, 1))), self.dt, method="zoh")
        self.Ad = Ad
        self.Bd = Bd[:, 0].copy()
        self.Cd = Cd
        self.x = np.zeros(A.shape[0])
        self._modal = None

    @property
    def n_states(self) -> int:
        """Number of states, 2·(2 n + 3)."""
        return self.Ad.shape[0]

    def reset(self) -> None:
        """Put the plant at rest at the origin (x = 0)."""
        self.x = np.zeros(self.n_states)

    def outputs(self) -> tuple[float, float]:
        """Noise-free outputs at the current state.

        Returns
        -------
        theta : float
            Base angle, encoder counts (H·theta_b).
        a : float
            Tip lateral acceleration times a_gain, accelerometer counts.
        """
        y = self.Cd @ self.x
        return float(y[0]), float(y[1])

    def advance(self, v: float) -> None:
        """Advance one sample with v (DAC counts) held: x ← Ad x + Bd v.

        Parameters
        ----------
        v : float
            The input held over the sample, DAC counts.
        """
        self.x = self.Ad @ self.x + self.Bd * float(v)

    def simulate_open_loop(self, v) -> tuple[np.ndarray, np.ndarray]:
        """Open-loop run from the current state; the plant ends at the final state.

        Parameters
        ----------
        v : array_like, shape (N,)
            Command per tick, DAC counts.

        Returns
        -------
        theta, a : ndarray, shape (N,)
            Noise-free outputs at ticks 0..N-1 (theta[k] sees x_k, before v[k] acts).
        """
        v = np.asarray(v, dtype=float).ravel()
        if v.size == 0:
            return np.zeros(0), np.zeros(0)
        sys = (self.Ad, self.Bd[:, None], self.Cd, np.zeros((2, 1)), self.dt)
        import scipy.signal  # lazy: start-up time (scipy.signal)
        _, y, xs = scipy.signal.dlsim(sys, np.append(v, 0.0), x0=self.x)
        self.x = xs[-1].copy()
        return y[:-1, 0].copy(), y[:-1, 1].copy()

    def modal_form(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Diagonal (modal) form of (Ad, Bd, Cd), computed once and cached.

        Returns
        -------
        lam : ndarray of complex, shape (n_x,)
            Eigenvalues of Ad.
        bm : ndarray of complex, shape (n_x,)
            V⁻¹ Bd.
        cm : ndarray of complex, shape (2, n_x)
            Cd V; the outputs are Re(cm @ z) with z = V⁻¹ x.
        vinv : ndarray of complex, shape (n_x, n_x)
            V⁻¹, to map a state into modal coordinates.
        """
        if self._modal is None:
            import scipy.linalg  # lazy: start-up time (scipy.linalg)
            lam, V = scipy.linalg.eig(self.Ad)
            lu = scipy.linalg.lu_factor(V)
            vinv = scipy.linalg.lu_solve(lu, np.eye(V.shape[0]))
            self._modal = (lam, vinv @ self.Bd, self.Cd @ V, vinv)
        return self._modal


class Sensors:
    """The rig's sensors: encoder quantization and a noisy, quantized accelerometer.

    Parameters
    ----------
    seed : int, default 0
        Seed of the numpy Generator (no global RNG).
    accel_noise_std : float, default 0.3
        Standard deviation of the accelerometer's Gaussian noise, counts (DESIGN.md).
    """

    def __init__(self, seed: int = 0, accel_noise_std: float = 0.3):
        self.rng = np.random.default_rng(seed)
        self.accel_noise_std = float(accel_noise_std)

    def read(self, theta: float, a: float) -> tuple[int, int]:
        """Latch one sample.

        Parameters
        ----------
        theta, a : float
            Noise-free outputs (encoder counts, accelerometer counts).

        Returns
        -------
        theta, a : int
            theta rounded to the nearest count; a plus Gaussian noise, rounded
            (:func:`quantize`).
        """
        noisy = a + self.accel_noise_std * self.rng.standard_normal()
        return quantize(theta), quantize(noisy)


def quantize(x: float) -> int:
    """Nearest whole count, as the encoder and ADC report (:func:`station.rounding.sensor_count`:
    halves away from zero).

    Parameters
    ----------
    x : float
        A noise-free output, counts.

    Raises
    ------
    ValueError
        ``x`` is NaN.
    OverflowError
        ``x`` is infinite.
    """
    return int(sensor_count(x))
