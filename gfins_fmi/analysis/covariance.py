"""Error covariance of linear error models (python-control systems): constant sensor
biases (random constants) and white noise (angle / velocity random walk) propagated with
the Van Loan discretisation (python-control's Gramians reject unstable or marginally
stable systems, so finite horizons are computed here), time-invariant and time-varying;
bias states appended to a model; finite-horizon observability; frequency responses.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["TimeVaryingModel", "ErrorStd", "covariance", "propagate", "with_bias_states", "Observability",
           "observability", "frequency_response"]


@dataclass
class TimeVaryingModel:
    """A linear time-varying error model x' = A(t) x + B(t) u, y = C x (the gyro-free
    INS under rotation: the body-to-frame matrix turns the body-fixed rate and force
    errors). ``propagate`` accepts it like a StateSpace; ``nlsys()`` gives the
    python-control system for simulation (``control.input_output_response``)."""
    A_of_t: object
    B_of_t: object
    C: np.ndarray
    state_labels: list
    input_labels: list
    output_labels: list

    def nlsys(self):
        import control   # lazy: python-control (~0.8 s) off the start-up path
        return control.nlsys(lambda t, x, u, params: self.A_of_t(t) @ x + self.B_of_t(t) @ u,
                             lambda t, x, u, params: self.C @ x, states=self.state_labels,
                             inputs=self.input_labels, outputs=self.output_labels)


@dataclass
class ErrorStd:
    """1-sigma of a model's outputs at the requested times: t_s (m,), std (m, n_out) in
    the model's output order (rad, m/s, m)."""
    t_s: np.ndarray
    std: np.ndarray


def covariance(sys, t_s, gyro_bias_std_rad_s=0.0, accel_bias_std_m_s2=0.0,
               gyro_white_rad_s_sqrt_hz=0.0, accel_white_m_s2_sqrt_hz=0.0,
               dt_s: float = 1.0) -> ErrorStd:
    """``propagate`` for ``sins_error_model``: the same bias and white-noise level on
    the three gyros and on the three accelerometers.

    White noise is given as the (two-sided) density q with E[w(t) w(s)] = q^2 delta(t-s):
    an angle random walk N (rad/sqrt(s)) is q = N for the gyro.
    """
    return propagate(sys, t_s, np.r_[np.full(3, float(gyro_bias_std_rad_s)),
                                     np.full(3, float(accel_bias_std_m_s2))],
                     np.r_[np.full(3, float(gyro_white_rad_s_sqrt_hz)),
                           np.full(3, float(accel_white_m_s2_sqrt_hz))], dt_s)


def propagate(sys, t_s, bias_std, white_density, dt_s: float = 1.0) -> ErrorStd:
    """Covariance of a linear error model whose inputs are independent random-constant
    biases (std ``bias_std``, one per input) plus white noise (density
    ``white_density``, one per input: E[w(t) w(s)] = q^2 delta(t-s)), from zero initial
    error, by Van Loan's discretisation over steps of dt_s. A sampled white noise of
    std sigma at interval T has q = sigma sqrt(T).
    """
    from scipy.linalg import expm   # lazy: scipy (0.1-0.5 s) off the start-up path
    varying = isinstance(sys, TimeVaryingModel)
    A_of_t = sys.A_of_t if varying else (lambda t, A=np.asarray(sys.A): A)
    B_of_t = sys.B_of_t if varying else (lambda t, B=np.asarray(sys.B): B)
    C = np.asarray(sys.C)
    n, m = A_of_t(0.0).shape[0], B_of_t(0.0).shape[1]
    bias_std = np.broadcast_to(np.asarray(bias_std, float), (m,))
    q = np.broadcast_to(np.asarray(white_density, float), (m,)) ** 2
    if not (np.all(np.isfinite(bias_std)) and np.all(np.isfinite(q))):
        raise ValueError("bias_std and white_density must be finite")
    t_s = np.atleast_1d(np.asarray(t_s, float))
    if np.any(np.diff(t_s) <= 0) or t_s[0] < 0:
        raise ValueError("t_s must be increasing and >= 0")
    if not dt_s > 0:
        raise ValueError("dt_s must be > 0 (s)")
    N = n + m

    def van_loan(t):
        """Phi and Qd of the step starting at t, with the model at its midpoint (a
        time-varying model: second order in dt)."""
        A, B = A_of_t(t + 0.5 * dt_s), B_of_t(t + 0.5 * dt_s)
        # augmented state: [error (n), biases (m)], biases constant
        Aa = np.zeros((N, N))
        Aa[:n, :n], Aa[:n, n:] = A, B
        Ga = np.zeros((N, m))
        Ga[:n] = B
        Mv = np.zeros((2 * N, 2 * N))
        Mv[:N, :N] = -Aa
        Mv[:N, N:] = Ga @ np.diag(q) @ Ga.T
        Mv[N:, N:] = Aa.T
        E = expm(Mv * dt_s)
        Phi = E[N:, N:].T
        return Phi, Phi @ E[:N, N:]

    if not varying:
        fixed = van_loan(0.0)
    P = np.zeros((N, N))
    P[n:, n:] = np.diag(bias_std ** 2)
    Caug = np.zeros((C.shape[0], N))
    Caug[:, :n] = C
    out = np.empty((t_s.size, C.shape[0]))
    t = 0.0
    for k, tk in enumerate(t_s):
        steps = int(round((tk - t) / dt_s))
        for _ in range(steps):
            Phi, Qd = van_loan(t) if varying else fixed
            P = Phi @ P @ Phi.T + Qd
            t += dt_s
        out[k] = np.sqrt(np.maximum(np.diag(Caug @ P @ Caug.T), 0.0))
    return ErrorStd(t_s, out)


def with_bias_states(sys):
    """The model with its inputs turned into random-constant states (appended after the
    error states, named after the inputs): the form a Kalman filter or an
    observability study uses. The original inputs remain, entering the error states
    as before: they are now the white-noise parts of the sensor errors."""
    import control   # lazy: python-control (~0.8 s) off the start-up path
    A, B, C = np.asarray(sys.A), np.asarray(sys.B), np.asarray(sys.C)
    n, m = A.shape[0], B.shape[1]
    Aa = np.zeros((n + m, n + m))
    Aa[:n, :n], Aa[:n, n:] = A, B
    Ba = np.zeros((n + m, m))
    Ba[:n] = B
    Ca = np.zeros((C.shape[0], n + m))
    Ca[:, :n] = C
    return control.ss(Aa, Ba, Ca, np.zeros((C.shape[0], m)), inputs=list(sys.input_labels),
                      outputs=list(sys.output_labels),
                      states=list(sys.state_labels) + list(sys.input_labels))


@dataclass
class Observability:
    """Finite-horizon observability of the states of a model through some measurements.

    Attributes
    ----------
    gramian : (n, n) W = sum_k Phi_k^T H^T H Phi_k dt over the horizon
    singular_values : (n,) of W, descending
    rank : int, numerical rank (relative tolerance ``tol``)
    unobservable : (n, n - rank) unit vectors spanning the unobservable directions, in
        the states' units
    states : the model's state names
    scale : (n,) the normalisation 1 / sqrt(W_ii) (0 for states never seen)
    """
    gramian: np.ndarray
    singular_values: np.ndarray
    rank: int
    unobservable: np.ndarray
    states: tuple
    scale: np.ndarray

    def describe(self, threshold: float = 0.05) -> list[str]:
        """Each unobservable direction as a combination of states in their own units;
        a state is listed when its part of the direction, measured unit-free (times
        sqrt(W_ii)), exceeds ``threshold`` of the largest part."""
        out = []
        w = np.where(self.scale > 0, 1.0 / np.where(self.scale > 0, self.scale, 1.0), 1.0)
        for v in self.unobservable.T:
            weight = np.abs(v * w)
            v = v / v[np.argmax(weight)]
            out.append(" ".join(f"{c:+.3g} {name}" for c, name, wt in zip(v, self.states, weight)
                                if wt > threshold * weight.max()))
        return out


def observability(A, H, t_s, states=None, tol: float = 1e-9) -> Observability:
    """Observability Gramian over a finite horizon along a trajectory.

    Parameters
    ----------
    A : (n, n) array, or callable t -> (n, n)
        Error dynamics (constant, or evaluated along the trajectory: time-varying).
    H : (p, n) array, or callable t -> (p, n)
        Which combinations of states are measured (e.g. velocity of a zero-velocity
        update or of GNSS).
    t_s : (K,) increasing measurement times (s); the transition between them is
        exp(A dt) with A at the interval's start.
    states : names of the n states (default: ``x0..``).
    tol : relative rank tolerance on the singular values of the Gramian normalised
        by its diagonal (so the states' units do not matter).

    python-control's Gramians are infinite-horizon and need a stable system; an INS
    error model is marginally stable (Schuler, Earth rate) or unstable, hence this.
    """
    from scipy.linalg import expm, svd   # lazy: scipy (0.1-0.5 s) off the start-up path
    t_s = np.atleast_1d(np.asarray(t_s, float))
    if t_s.ndim != 1 or t_s.size < 1 or np.any(np.diff(t_s) <= 0):
        raise ValueError("t_s must be a non-empty increasing sequence of times (s)")
    At = A if callable(A) else (lambda t, A=np.asarray(A, float): A)
    Ht = H if callable(H) else (lambda t, H=np.asarray(H, float): H)
    n = np.asarray(At(t_s[0])).shape[0]
    if np.asarray(At(t_s[0])).shape != (n, n) or np.asarray(Ht(t_s[0])).shape[-1] != n:
        raise ValueError("A must be (n, n) and H (p, n)")
    W = np.zeros((n, n))
    Phi = np.eye(n)
    dts = np.diff(t_s, append=t_s[-1] + (t_s[-1] - t_s[-2] if t_s.size > 1 else 1.0))
    for k, t in enumerate(t_s):
        Hk = np.atleast_2d(np.asarray(Ht(t), float))
        M = Hk @ Phi
        W += M.T @ M * dts[k]
        Phi = expm(np.asarray(At(t), float) * dts[k]) @ Phi
    # unit-free: scale each state by its own observability (states never seen stay 0),
    # so rad, m/s and m/s^2 do not decide the rank between them
    d = np.sqrt(np.diag(W))
    scale = np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 0.0)
    _, sv, vt = svd(W * np.outer(scale, scale))
    rank = int(np.sum(sv > tol * sv[0])) if sv[0] > 0 else 0
    basis = vt[rank:].T * scale[:, None]       # back to the states' own units
    never = np.flatnonzero(d == 0)              # states with no effect at all: there the
    keep = np.linalg.norm(basis, axis=0) > 0    # scaled vectors vanish; use unit vectors
    basis = np.column_stack([basis[:, keep]] + [np.eye(n)[:, j] for j in never])[:, :n - rank]
    basis = basis / np.linalg.norm(basis, axis=0)
    names = tuple(states) if states is not None else tuple(f"x{i}" for i in range(n))
    return Observability(W, sv, rank, basis, names, scale)


def frequency_response(sys, omega_rad_s, inputs=None, outputs=None):
    """Gain and phase from sensor errors to navigation errors at the angular
    frequencies ``omega_rad_s`` (rad/s): ``control.frequency_response`` of the selected
    input/output channels (names from the model's labels). Returns the
    ``control.FrequencyResponseData`` (``.magnitude``, ``.phase``, ``.plot()``)."""
    import control   # lazy: python-control (~0.8 s) off the start-up path
    sub = sys
    if inputs is not None or outputs is not None:
        ins = list(sys.input_labels) if inputs is None else list(inputs)
        outs = list(sys.output_labels) if outputs is None else list(outputs)
        for name in ins + outs:
            if name not in sys.input_labels + sys.output_labels:
                raise ValueError(f"no channel {name!r}; inputs {sys.input_labels}, "
                                 f"outputs {sys.output_labels}")
        sub = sys[[sys.output_labels.index(o) for o in outs],
                  [sys.input_labels.index(i) for i in ins]]
    return control.frequency_response(sub, np.asarray(omega_rad_s, float))
