"""Butcher tableaus of the explicit Runge-Kutta methods of the language.

Each method is one :class:`Tableau`: the nodes ``c``, the strictly lower-triangular matrix
``a``, the weights ``b`` of the solution that is propagated, and, for the adaptive ones,
the weights ``e`` of the embedded error estimate ``err = h * sum_i e_i k_i``. For the
"first same as last" (FSAL) pairs (Bogacki-Shampine, Dormand-Prince 5 and 8) the error
weights have one more entry than there are stages: it multiplies ``f(t + h, y_new)``,
which is then reused as the first stage of the next step.

Coefficients are the published ones:

- Bogacki & Shampine, "A 3(2) pair of Runge-Kutta formulas", Appl. Math. Lett. 2 (1989).
- Cash & Karp, "A variable order Runge-Kutta method...", ACM TOMS 16 (1990).
- Fehlberg, NASA TR R-315 (1969): RKF45, the 4th-order solution is propagated.
- Dormand & Prince, "A family of embedded Runge-Kutta formulae", J. Comp. Appl. Math. 6
  (1980): DOPRI5, the 5th-order solution is propagated.
- Hairer, Norsett & Wanner, Solving ODEs I, DOP853 (coefficients as in Hairer's Fortran
  code and SciPy's ``dop853_coefficients.py``), with Hairer's combined 5th/3rd-order
  error estimator.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Tableau", "TABLEAUS"]


@dataclass(frozen=True)
class Tableau:
    """One explicit Runge-Kutta method.

    ``s`` is the number of stages (not counting the FSAL evaluation).
    """

    name: str
    """Method name as written in a spec (``rk4``, ``dopri5``...)."""
    c: np.ndarray
    """(s,) nodes: stage i is evaluated at ``t + c[i] * h``."""
    a: np.ndarray
    """(s, s) strictly lower-triangular stage matrix."""
    b: np.ndarray
    """(s,) weights of the propagated solution ``y_new = y + h * sum_i b_i k_i``."""
    order: int
    """Order of the propagated solution."""
    e: np.ndarray | None = None
    """(s,) or (s + 1,) error weights (propagated minus embedded); ``None`` if not adaptive."""
    error_order: int = 0
    """Order of the lower of the two embedded solutions; the step-size exponent is
    ``-1 / (error_order + 1)``."""
    fsal: bool = False
    """``f(t + h, y_new)`` is part of the error estimate and is the next step's first stage."""
    e3: np.ndarray | None = None
    """(s + 1,) DOP853 only: weights of the 3rd-order error estimate used by Hairer's
    combined error norm (``e`` then holds the 5th-order one)."""
    stage_terms: tuple[tuple[tuple[int, float], ...], ...] = field(init=False, repr=False)
    """Per stage, the nonzero ``(j, a_ij)`` pairs (precomputed for the fixed-step path)."""
    b_terms: tuple[tuple[int, float], ...] = field(init=False, repr=False)
    """The nonzero ``(j, b_j)`` pairs."""

    def __post_init__(self) -> None:
        s = len(self.c)
        terms = tuple(
            tuple((j, float(self.a[i, j])) for j in range(i) if self.a[i, j] != 0.0) for i in range(s)
        )
        object.__setattr__(self, "stage_terms", terms)
        object.__setattr__(self, "b_terms", tuple((j, float(v)) for j, v in enumerate(self.b) if v != 0.0))

    @property
    def stages(self) -> int:
        """Number of stages ``s`` (without the FSAL evaluation)."""
        return len(self.c)

    @property
    def adaptive(self) -> bool:
        """Whether the method has an embedded error estimate."""
        return self.e is not None


def _lower(rows: list[list[float]]) -> np.ndarray:
    """Strictly lower-triangular (s, s) matrix from its rows below the diagonal."""
    s = len(rows)
    a = np.zeros((s, s))
    for i, row in enumerate(rows):
        a[i, : len(row)] = row
    return a


_EULER = Tableau("euler", np.array([0.0]), np.zeros((1, 1)), np.array([1.0]), order=1)

# Explicit midpoint rule: EJS's "Euler-Richardson" (evaluate the rate at the half step).
_EULER_RICHARDSON = Tableau(
    "euler_richardson", np.array([0.0, 0.5]), _lower([[], [0.5]]), np.array([0.0, 1.0]), order=2
)

_RK4 = Tableau(
    "rk4",
    np.array([0.0, 0.5, 0.5, 1.0]),
    _lower([[], [0.5], [0.0, 0.5], [0.0, 0.0, 1.0]]),
    np.array([1 / 6, 1 / 3, 1 / 3, 1 / 6]),
    order=4,
)

_BS_B = np.array([2 / 9, 1 / 3, 4 / 9])
_BOGACKI_SHAMPINE = Tableau(
    "bogacki_shampine",
    np.array([0.0, 0.5, 0.75]),
    _lower([[], [0.5], [0.0, 0.75]]),
    _BS_B,
    order=3,
    e=np.append(_BS_B, 0.0) - np.array([7 / 24, 1 / 4, 1 / 3, 1 / 8]),
    error_order=2,
    fsal=True,
)

_CK_B5 = np.array([37 / 378, 0.0, 250 / 621, 125 / 594, 0.0, 512 / 1771])
_CK_B4 = np.array([2825 / 27648, 0.0, 18575 / 48384, 13525 / 55296, 277 / 14336, 1 / 4])
_CASH_KARP = Tableau(
    "cash_karp",
    np.array([0.0, 1 / 5, 3 / 10, 3 / 5, 1.0, 7 / 8]),
    _lower(
        [
            [],
            [1 / 5],
            [3 / 40, 9 / 40],
            [3 / 10, -9 / 10, 6 / 5],
            [-11 / 54, 5 / 2, -70 / 27, 35 / 27],
            [1631 / 55296, 175 / 512, 575 / 13824, 44275 / 110592, 253 / 4096],
        ]
    ),
    _CK_B5,
    order=5,
    e=_CK_B5 - _CK_B4,
    error_order=4,
)

_F_B4 = np.array([25 / 216, 0.0, 1408 / 2565, 2197 / 4104, -1 / 5, 0.0])
_F_B5 = np.array([16 / 135, 0.0, 6656 / 12825, 28561 / 56430, -9 / 50, 2 / 55])
_FEHLBERG = Tableau(
    "fehlberg",
    np.array([0.0, 1 / 4, 3 / 8, 12 / 13, 1.0, 1 / 2]),
    _lower(
        [
            [],
            [1 / 4],
            [3 / 32, 9 / 32],
            [1932 / 2197, -7200 / 2197, 7296 / 2197],
            [439 / 216, -8.0, 3680 / 513, -845 / 4104],
            [-8 / 27, 2.0, -3544 / 2565, 1859 / 4104, -11 / 40],
        ]
    ),
    _F_B4,
    order=4,
    e=_F_B4 - _F_B5,
    error_order=4,
)

_DP_B = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84])
_DOPRI5 = Tableau(
    "dopri5",
    np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0]),
    _lower(
        [
            [],
            [1 / 5],
            [3 / 40, 9 / 40],
            [44 / 45, -56 / 15, 32 / 9],
            [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729],
            [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
        ]
    ),
    _DP_B,
    order=5,
    e=np.array([71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40]),
    error_order=4,
    fsal=True,
)

# --- DOP853 (12 stages; row 12 of _A853 is the weight vector b) -------------------------
_C853 = np.array([0.0,
              0.526001519587677318785587544488e-01,
              0.789002279381515978178381316732e-01,
              0.118350341907227396726757197510,
              0.281649658092772603273242802490,
              0.333333333333333333333333333333,
              0.25,
              0.307692307692307692307692307692,
              0.651282051282051282051282051282,
              0.6,
              0.857142857142857142857142857142,
              1.0,
              1.0,
              0.1,
              0.2,
              0.777777777777777777777777777778])

_A853 = np.zeros((13, 13))
_A853[1, 0] = 5.26001519587677318785587544488e-2

_A853[2, 0] = 1.97250569845378994544595329183e-2
_A853[2, 1] = 5.91751709536136983633785987549e-2

_A853[3, 0] = 2.95875854768068491816892993775e-2
_A853[3, 2] = 8.87627564304205475450678981324e-2

_A853[4, 0] = 2.41365134159266685502369798665e-1
_A853[4, 2] = -8.84549479328286085344864962717e-1
_A853[4, 3] = 9.24834003261792003115737966543e-1

_A853[5, 0] = 3.7037037037037037037037037037e-2
_A853[5, 3] = 1.70828608729473871279604482173e-1
_A853[5, 4] = 1.25467687566822425016691814123e-1

_A853[6, 0] = 3.7109375e-2
_A853[6, 3] = 1.70252211019544039314978060272e-1
_A853[6, 4] = 6.02165389804559606850219397283e-2
_A853[6, 5] = -1.7578125e-2

_A853[7, 0] = 3.70920001185047927108779319836e-2
_A853[7, 3] = 1.70383925712239993810214054705e-1
_A853[7, 4] = 1.07262030446373284651809199168e-1
_A853[7, 5] = -1.53194377486244017527936158236e-2
_A853[7, 6] = 8.27378916381402288758473766002e-3

_A853[8, 0] = 6.24110958716075717114429577812e-1
_A853[8, 3] = -3.36089262944694129406857109825
_A853[8, 4] = -8.68219346841726006818189891453e-1
_A853[8, 5] = 2.75920996994467083049415600797e1
_A853[8, 6] = 2.01540675504778934086186788979e1
_A853[8, 7] = -4.34898841810699588477366255144e1

_A853[9, 0] = 4.77662536438264365890433908527e-1
_A853[9, 3] = -2.48811461997166764192642586468
_A853[9, 4] = -5.90290826836842996371446475743e-1
_A853[9, 5] = 2.12300514481811942347288949897e1
_A853[9, 6] = 1.52792336328824235832596922938e1
_A853[9, 7] = -3.32882109689848629194453265587e1
_A853[9, 8] = -2.03312017085086261358222928593e-2

_A853[10, 0] = -9.3714243008598732571704021658e-1
_A853[10, 3] = 5.18637242884406370830023853209
_A853[10, 4] = 1.09143734899672957818500254654
_A853[10, 5] = -8.14978701074692612513997267357
_A853[10, 6] = -1.85200656599969598641566180701e1
_A853[10, 7] = 2.27394870993505042818970056734e1
_A853[10, 8] = 2.49360555267965238987089396762
_A853[10, 9] = -3.0467644718982195003823669022

_A853[11, 0] = 2.27331014751653820792359768449
_A853[11, 3] = -1.05344954667372501984066689879e1
_A853[11, 4] = -2.00087205822486249909675718444
_A853[11, 5] = -1.79589318631187989172765950534e1
_A853[11, 6] = 2.79488845294199600508499808837e1
_A853[11, 7] = -2.85899827713502369474065508674
_A853[11, 8] = -8.87285693353062954433549289258
_A853[11, 9] = 1.23605671757943030647266201528e1
_A853[11, 10] = 6.43392746015763530355970484046e-1

_A853[12, 0] = 5.42937341165687622380535766363e-2
_A853[12, 5] = 4.45031289275240888144113950566
_A853[12, 6] = 1.89151789931450038304281599044
_A853[12, 7] = -5.8012039600105847814672114227
_A853[12, 8] = 3.1116436695781989440891606237e-1
_A853[12, 9] = -1.52160949662516078556178806805e-1
_A853[12, 10] = 2.01365400804030348374776537501e-1
_A853[12, 11] = 4.47106157277725905176885569043e-2

_E3_853 = np.zeros(13)
_E3_853[:-1] = _A853[12, :12]
_E3_853[0] -= 0.244094488188976377952755905512
_E3_853[8] -= 0.733846688281611857341361741547
_E3_853[11] -= 0.220588235294117647058823529412e-1

_E5_853 = np.zeros(13)
_E5_853[0] = 0.1312004499419488073250102996e-1
_E5_853[5] = -0.1225156446376204440720569753e+1
_E5_853[6] = -0.4957589496572501915214079952
_E5_853[7] = 0.1664377182454986536961530415e+1
_E5_853[8] = -0.3503288487499736816886487290
_E5_853[9] = 0.3341791187130174790297318841
_E5_853[10] = 0.8192320648511571246570742613e-1
_E5_853[11] = -0.2235530786388629525884427845e-1

_DOP853 = Tableau(
    "dop853",
    _C853[:12].copy(),
    _A853[:12, :12].copy(),
    _A853[12, :12].copy(),
    order=8,
    e=_E5_853,
    error_order=7,
    fsal=True,
    e3=_E3_853,
)

TABLEAUS: dict[str, Tableau] = {
    t.name: t
    for t in (_EULER, _EULER_RICHARDSON, _RK4, _BOGACKI_SHAMPINE, _CASH_KARP, _FEHLBERG, _DOPRI5, _DOP853)
}
"""Every explicit method of the language by name."""
