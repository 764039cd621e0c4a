//! Butcher tableaus as data, with their literature sources.
//!
//! The coefficients are checked against the Runge–Kutta order conditions (all rooted
//! trees up to the claimed order) by the unit tests at the bottom of this file.

/// An explicit Runge–Kutta method: `a` is strictly lower triangular, row `i` holding
/// `a[i][0..i]`.
#[derive(Debug)]
pub(crate) struct ExplicitTableau {
    /// Nodes `c_i` (fractions of the step).
    pub c: &'static [f64],
    /// Stage coefficients, row `i` of length `i`.
    pub a: &'static [&'static [f64]],
    /// Weights of the propagated solution.
    pub b: &'static [f64],
    /// Error weights `e = b − b̂` of the embedded solution `b̂` (empty: no estimate):
    /// the local error estimate is `h Σ e_i k_i` (state units).
    pub e: &'static [f64],
    /// Weights `b̂₃` of a second, lower-order embedded solution that Hairer's DOP853
    /// combines with the first (empty: the error is `h Σ e_i k_i` alone). With it,
    /// the error norm is `err = E² / sqrt(E² + 0.01 E₃²)`, where `E` and `E₃` are the
    /// norms of `h Σ e_i k_i` and `h Σ (b_i − b̂₃_i) k_i` (HNW I, §II.10, code DOP853).
    pub b_hat_low: &'static [f64],
    /// Order of the propagated solution.
    pub order: u32,
    /// The error norm behaves like `h^(error_order + 1)`: the order of the embedded
    /// solution for a plain estimate, 7 for DOP853's combined one (`E²/E₃ ∝ h^8`).
    /// Sets the exponent of the step-size controller (0 without an estimate).
    pub error_order: u32,
    /// Gain β of the PI controller on the previous error (dimensionless): Hairer's
    /// 0.04 for the 5(4) pairs ([`super::control::PI_BETA`]), 0 (a plain controller)
    /// where that is what the pair's own code uses.
    pub pi_beta: f64,
    /// Threshold of Hairer's stiffness test on `h ρ` (dimensionless), `ρ` the
    /// difference quotient of the last two stages, both at `c = 1` (HNW II,
    /// §IV.2, and the codes DOPRI5 and DOP853): a little inside the method's
    /// stability interval on the negative real axis. 0 for a pair without the test.
    pub stiffness_bound: f64,
    /// First-same-as-last: the last stage is evaluated at the new solution
    /// (its row of `a` equals `b`), so its slope is the next step's first stage.
    pub fsal: bool,
    /// Continuous extension; `None`: plain cubic Hermite.
    pub dense: Option<DenseOutput>,
}

impl ExplicitTableau {
    /// Number of stages of a step (the FSAL stage included, extra stages of the
    /// continuous extension not).
    pub fn stages(&self) -> usize {
        self.c.len()
    }

    /// Number of stages with those of the continuous extension.
    pub fn all_stages(&self) -> usize {
        self.stages() + self.dense.as_ref().map_or(0, |d| d.c.len())
    }
}

/// The continuous extension of an FSAL pair in Hairer's nested form (HNW I, §II.6;
/// routines `CONTD5` of DOPRI5 and `CONTD8` of DOP853): with `θ = (t − t0)/h`,
/// `θ₁ = 1 − θ`,
///
/// `y(t0 + θh) = y0 + θ(F0 + θ₁(F1 + θ(F2 + θ₁(F3 + θ(F4 + θ₁(F5 + …))))))`,
///
/// where `F0 = Δ = y1 − y0`, `F1 = h f0 − Δ`, `F2 = 2Δ − h f0 − h f1` make the
/// cubic Hermite interpolant of the step's ends and `F_{3+j} = h Σ_i d[j][i] k_i`
/// over the step's stages and then the extra stages below.
#[derive(Debug)]
pub(crate) struct DenseOutput {
    /// Nodes of the extra stages (fractions of the step), evaluated only for steps
    /// with a sample inside.
    pub c: &'static [f64],
    /// Their rows of `a`, each over all earlier stages: the step's (FSAL stage
    /// included), then the earlier extra ones.
    pub a: &'static [&'static [f64]],
    /// Rows `d[j]` of the terms `F_{3+j}`, over all stages.
    pub d: &'static [&'static [f64]],
}

/// The classic fourth-order Runge–Kutta method (Kutta 1901; Hairer, Nørsett &
/// Wanner, *Solving ODEs I*, 2nd ed., Table II.1.2, left).
pub(crate) const RK4: ExplicitTableau = ExplicitTableau {
    c: &[0.0, 0.5, 0.5, 1.0],
    a: &[&[], &[0.5], &[0.0, 0.5], &[0.0, 0.0, 1.0]],
    b: &[1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0],
    e: &[],
    b_hat_low: &[],
    order: 4,
    error_order: 0,
    pi_beta: 0.0,
    stiffness_bound: 0.0,
    fsal: false,
    dense: None,
};

/// Dormand & Prince, "A family of embedded Runge–Kutta formulae", J. Comput. Appl.
/// Math. 6 (1980) 19–26: the 5(4) pair of Hairer, Nørsett & Wanner, *Solving ODEs I*,
/// 2nd ed., Table II.5.2 (DOPRI5); error weights `E_i` and the order-4 continuous
/// extension (coefficients `d_i`, Shampine 1986) as in Hairer's code `DOPRI5`.
pub(crate) const DORMAND_PRINCE: ExplicitTableau = ExplicitTableau {
    c: &[0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0],
    a: &[
        &[],
        &[1.0 / 5.0],
        &[3.0 / 40.0, 9.0 / 40.0],
        &[44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0],
        &[
            19372.0 / 6561.0,
            -25360.0 / 2187.0,
            64448.0 / 6561.0,
            -212.0 / 729.0,
        ],
        &[
            9017.0 / 3168.0,
            -355.0 / 33.0,
            46732.0 / 5247.0,
            49.0 / 176.0,
            -5103.0 / 18656.0,
        ],
        DORMAND_PRINCE_B.split_at(6).0,
    ],
    b: DORMAND_PRINCE_B,
    // b − b̂ with the b̂ of HNW I, Table II.5.2, rounded as the difference of the two
    // rounded weights (as DOPRI5 ran before the pairs shared this engine, so its
    // step sequences are unchanged); Hairer's E_i to within 1e-16.
    e: &[
        35.0 / 384.0 - 5179.0 / 57600.0,
        0.0,
        500.0 / 1113.0 - 7571.0 / 16695.0,
        125.0 / 192.0 - 393.0 / 640.0,
        -2187.0 / 6784.0 - -92097.0 / 339200.0,
        11.0 / 84.0 - 187.0 / 2100.0,
        -1.0 / 40.0,
    ],
    b_hat_low: &[],
    order: 5,
    error_order: 4,
    pi_beta: super::control::PI_BETA,
    // Hairer's DOPRI5 (its stability interval on the negative real axis ends at −3.3066).
    stiffness_bound: 3.25,
    fsal: true,
    dense: Some(DenseOutput {
        c: &[],
        a: &[],
        d: &[&[
            -12715105075.0 / 11282082432.0,
            0.0,
            87487479700.0 / 32700410799.0,
            -10690763975.0 / 1880347072.0,
            701980252875.0 / 199316789632.0,
            -1453857185.0 / 822651844.0,
            69997945.0 / 29380423.0,
        ]],
    }),
};

/// DOPRI5's weights `b` (the first 6 are the row of `a` of the FSAL stage).
const DORMAND_PRINCE_B: &[f64] = &[
    35.0 / 384.0,
    0.0,
    500.0 / 1113.0,
    125.0 / 192.0,
    -2187.0 / 6784.0,
    11.0 / 84.0,
    0.0,
];

/// Tsitouras, "Runge–Kutta pairs of order 5(4) satisfying only the first column
/// simplifying assumption", Comput. Math. Appl. 62 (2011) 770–775 (Tsit5): 7 stages,
/// FSAL, and its free order-4 continuous extension `y0 + h Σ b_i(θ) k_i` with
/// quartic `b_i(θ)`. The coefficients are the paper's, to the digits kept by
/// OrdinaryDiffEq.jl (`Tsit5ConstantCache`, `Tsit5Interp`); `e` is its `btilde`
/// with the sign of `b − b̂`. The extension is C¹ (`b_i'(0) = δ_{i1}`,
/// `b_i'(1) = δ_{i7}`), so it is the cubic Hermite interpolant plus
/// `θ²(1−θ)² h Σ d_i k_i` with `d_i` the θ⁴ coefficient of `b_i(θ)` (checked against
/// the published polynomials in the tests below).
#[allow(clippy::excessive_precision)]
pub(crate) const TSITOURAS5: ExplicitTableau = ExplicitTableau {
    c: &[
        0.0,
        0.161,
        0.327,
        0.9,
        0.98002554090450968572981028628702459549,
        1.0,
        1.0,
    ],
    a: &[
        &[],
        &[0.161],
        &[
            -0.84806554923569885444268742502307746751e-2,
            0.33548065549235698854442687425023077468,
        ],
        &[
            2.8971530571054934321304325941929387649,
            -6.3594484899750748431481599123838256260,
            4.3622954328695814110177273181908868610,
        ],
        &[
            5.3258648284392566044288779208405113178,
            -11.748883564062827877747170339785772962,
            7.4955393428898362083046047845643581557,
            -0.92495066361755249256502079332071916113e-1,
        ],
        &[
            5.8614554429464200286592514869826478904,
            -12.920969317847109291706118681783359395,
            8.1593678985761586431804007945392534852,
            -0.71584973281400997224530542525829738691e-1,
            -0.28269050394068382909003057212712241467e-1,
        ],
        TSITOURAS5_B.split_at(6).0,
    ],
    b: TSITOURAS5_B,
    e: &[
        1.7800110522257714433785506075395347759e-3,
        8.1643445965674690322363606335468624019e-4,
        -7.8808780102619960103147276725263042386e-3,
        1.4471100717326290753716514797263511672e-1,
        -5.8235716545255522501993761065204217943e-1,
        4.5808210592918694666163651883255429744e-1,
        -1.0 / 66.0,
    ],
    dense: Some(DenseOutput {
        c: &[],
        a: &[],
        d: &[&[
            -1.0530884977290216,
            0.1017,
            2.490627285651252793,
            -16.54810288924490272,
            47.37952196281928122,
            -34.87065786149660974,
            2.5,
        ]],
    }),
    // Hairer's test at DOPRI5's 98.3 % of the stability interval, which for Tsit5
    // ends at −3.5068.
    stiffness_bound: 3.45,
    // A 5(4) FSAL pair with one plain estimate, like DOPRI5: order, error order,
    // PI gain, FSAL and the empty `b_hat_low` are DOPRI5's.
    ..DORMAND_PRINCE
};

/// Tsit5's weights `b` (the first 6 are the row of `a` of the FSAL stage).
#[allow(clippy::excessive_precision)]
const TSITOURAS5_B: &[f64] = &[
    0.96460766818065229518167313165128763337e-1,
    0.01,
    0.47988965041449957477524953229059651991,
    1.3790085741037418931922748218568727708,
    -3.2900695154360806799010475857113638501,
    2.3247105240997739824153559183987657961,
    0.0,
];

/// Dormand & Prince's 8(5,3) pair as in Hairer's code DOP853 (Hairer, Nørsett &
/// Wanner, *Solving ODEs I*, 2nd ed., §II.10; coefficients of `dop853.f`, version of
/// 1994, as also used by SciPy's `DOP853`): 12 stages and a 13th FSAL stage at the
/// new solution, an error estimate combining a 5th- and a 3rd-order embedded
/// solution, and an order-7 continuous extension that needs 3 extra stages.
#[allow(clippy::excessive_precision)]
pub(crate) const DOP853: ExplicitTableau = ExplicitTableau {
    c: &[
        0.0,
        0.526001519587677318785587544488e-1,
        0.789002279381515978178381316732e-1,
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
    ],
    a: &[
        &[],
        &[5.26001519587677318785587544488e-2],
        &[
            1.97250569845378994544595329183e-2,
            5.91751709536136983633785987549e-2,
        ],
        &[
            2.95875854768068491816892993775e-2,
            0.0,
            8.87627564304205475450678981324e-2,
        ],
        &[
            2.41365134159266685502369798665e-1,
            0.0,
            -8.84549479328286085344864962717e-1,
            9.24834003261792003115737966543e-1,
        ],
        &[
            3.7037037037037037037037037037e-2,
            0.0,
            0.0,
            1.70828608729473871279604482173e-1,
            1.25467687566822425016691814123e-1,
        ],
        &[
            3.7109375e-2,
            0.0,
            0.0,
            1.70252211019544039314978060272e-1,
            6.02165389804559606850219397283e-2,
            -1.7578125e-2,
        ],
        &[
            3.70920001185047927108779319836e-2,
            0.0,
            0.0,
            1.70383925712239993810214054705e-1,
            1.07262030446373284651809199168e-1,
            -1.53194377486244017527936158236e-2,
            8.27378916381402288758473766002e-3,
        ],
        &[
            6.24110958716075717114429577812e-1,
            0.0,
            0.0,
            -3.36089262944694129406857109825,
            -8.68219346841726006818189891453e-1,
            2.75920996994467083049415600797e1,
            2.01540675504778934086186788979e1,
            -4.34898841810699588477366255144e1,
        ],
        &[
            4.77662536438264365890433908527e-1,
            0.0,
            0.0,
            -2.48811461997166764192642586468,
            -5.90290826836842996371446475743e-1,
            2.12300514481811942347288949897e1,
            1.52792336328824235832596922938e1,
            -3.32882109689848629194453265587e1,
            -2.03312017085086261358222928593e-2,
        ],
        &[
            -9.3714243008598732571704021658e-1,
            0.0,
            0.0,
            5.18637242884406370830023853209,
            1.09143734899672957818500254654,
            -8.14978701074692612513997267357,
            -1.85200656599969598641566180701e1,
            2.27394870993505042818970056734e1,
            2.49360555267965238987089396762,
            -3.0467644718982195003823669022,
        ],
        &[
            2.27331014751653820792359768449,
            0.0,
            0.0,
            -1.05344954667372501984066689879e1,
            -2.00087205822486249909675718444,
            -1.79589318631187989172765950534e1,
            2.79488845294199600508499808837e1,
            -2.85899827713502369474065508674,
            -8.87285693353062954433549289258,
            1.23605671757943030647266201528e1,
            6.43392746015763530355970484046e-1,
        ],
        DOP853_B.split_at(12).0,
    ],
    b: DOP853_B,
    // Hairer's ER1..ER12: the difference of the solution and a 5th-order one.
    e: &[
        0.1312004499419488073250102996e-1,
        0.0,
        0.0,
        0.0,
        0.0,
        -0.1225156446376204440720569753e1,
        -0.4957589496572501915214079952,
        0.1664377182454986536961530415e1,
        -0.3503288487499736816886487290,
        0.3341791187130174790297318841,
        0.8192320648511571246570742613e-1,
        -0.2235530786388629525884427845e-1,
        0.0,
    ],
    // Hairer's BHH1, BHH2, BHH3 at stages 1, 9 and 12.
    b_hat_low: &[
        0.244094488188976377952755905512,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        0.733846688281611857341361741547,
        0.0,
        0.0,
        0.220588235294117647058823529412e-1,
        0.0,
    ],
    order: 8,
    error_order: 7,
    pi_beta: 0.0,
    // Hairer's DOP853 (its stability interval on the negative real axis ends at −6.3937).
    stiffness_bound: 6.1,
    fsal: true,
    dense: Some(DenseOutput {
        c: &[0.1, 0.2, 0.777777777777777777777777777778],
        a: &[
            &[
                5.61675022830479523392909219681e-2,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
                2.53500210216624811088794765333e-1,
                -2.46239037470802489917441475441e-1,
                -1.24191423263816360469010140626e-1,
                1.5329179827876569731206322685e-1,
                8.20105229563468988491666602057e-3,
                7.56789766054569976138603589584e-3,
                -8.298e-3,
            ],
            &[
                3.18346481635021405060768473261e-2,
                0.0,
                0.0,
                0.0,
                0.0,
                2.83009096723667755288322961402e-2,
                5.35419883074385676223797384372e-2,
                -5.49237485713909884646569340306e-2,
                0.0,
                0.0,
                -1.08347328697249322858509316994e-4,
                3.82571090835658412954920192323e-4,
                -3.40465008687404560802977114492e-4,
                1.41312443674632500278074618366e-1,
            ],
            &[
                -4.28896301583791923408573538692e-1,
                0.0,
                0.0,
                0.0,
                0.0,
                -4.69762141536116384314449447206,
                7.68342119606259904184240953878,
                4.06898981839711007970213554331,
                3.56727187455281109270669543021e-1,
                0.0,
                0.0,
                0.0,
                -1.39902416515901462129418009734e-3,
                2.9475147891527723389556272149,
                -9.15095847217987001081870187138,
            ],
        ],
        d: &[
            &[
                -0.84289382761090128651353491142e1,
                0.0,
                0.0,
                0.0,
                0.0,
                0.56671495351937776962531783590,
                -0.30689499459498916912797304727e1,
                0.23846676565120698287728149680e1,
                0.21170345824450282767155149946e1,
                -0.87139158377797299206789907490,
                0.22404374302607882758541771650e1,
                0.63157877876946881815570249290,
                -0.88990336451333310820698117400e-1,
                0.18148505520854727256656404962e2,
                -0.91946323924783554000451984436e1,
                -0.44360363875948939664310572000e1,
            ],
            &[
                0.10427508642579134603413151009e2,
                0.0,
                0.0,
                0.0,
                0.0,
                0.24228349177525818288430175319e3,
                0.16520045171727028198505394887e3,
                -0.37454675472269020279518312152e3,
                -0.22113666853125306036270938578e2,
                0.77334326684722638389603898808e1,
                -0.30674084731089398182061213626e2,
                -0.93321305264302278729567221706e1,
                0.15697238121770843886131091075e2,
                -0.31139403219565177677282850411e2,
                -0.93529243588444783865713862664e1,
                0.35816841486394083752465898540e2,
            ],
            &[
                0.19985053242002433820987653617e2,
                0.0,
                0.0,
                0.0,
                0.0,
                -0.38703730874935176555105901742e3,
                -0.18917813819516756882830838328e3,
                0.52780815920542364900561016686e3,
                -0.11573902539959630126141871134e2,
                0.68812326946963000169666922661e1,
                -0.10006050966910838403183860980e1,
                0.77771377980534432092869265740,
                -0.27782057523535084065932004339e1,
                -0.60196695231264120758267380846e2,
                0.84320405506677161018159903784e2,
                0.11992291136182789328035130030e2,
            ],
            &[
                -0.25693933462703749003312586129e2,
                0.0,
                0.0,
                0.0,
                0.0,
                -0.15418974869023643374053993627e3,
                -0.23152937917604549567536039109e3,
                0.35763911791061412378285349910e3,
                0.93405324183624310003907691704e2,
                -0.37458323136451633156875139351e2,
                0.10409964950896230045147246184e3,
                0.29840293426660503123344363579e2,
                -0.43533456590011143754432175058e2,
                0.96324553959188282948394950600e2,
                -0.39177261675615439165231486172e2,
                -0.14972683625798562581422125276e3,
            ],
        ],
    }),
};

/// DOP853's weights `b` (the first 12 are the row of `a` of the FSAL stage).
#[allow(clippy::excessive_precision)]
const DOP853_B: &[f64] = &[
    5.42937341165687622380535766363e-2,
    0.0,
    0.0,
    0.0,
    0.0,
    4.45031289275240888144113950566,
    1.89151789931450038304281599044,
    -5.8012039600105847814672114227,
    3.1116436695781989440891606237e-1,
    -1.52160949662516078556178806805e-1,
    2.01365400804030348374776537501e-1,
    4.47106157277725905176885569043e-2,
    0.0,
];

/// A singly diagonally implicit Runge–Kutta method: `a` is lower triangular with
/// `gamma` on the diagonal, row `i` holding `a[i][0..=i]`.
#[derive(Debug)]
pub(crate) struct SdirkTableau {
    /// The common diagonal coefficient.
    pub gamma: f64,
    /// Nodes `c_i` (fractions of the step).
    pub c: &'static [f64],
    /// Stage coefficients, row `i` of length `i + 1` (diagonal included).
    pub a: &'static [&'static [f64]],
    /// Weights of the propagated solution (equal to the last row of `a`:
    /// stiffly accurate, so the new solution is the last stage value).
    pub b: &'static [f64],
    /// Weights of the embedded solution used for the error estimate.
    pub b_hat: &'static [f64],
    /// Order of the propagated solution.
    pub order: u32,
    /// Order of the embedded solution.
    pub embedded_order: u32,
}

impl SdirkTableau {
    /// Number of stages.
    pub fn stages(&self) -> usize {
        self.c.len()
    }
}

/// The L-stable, stiffly accurate SDIRK method of order 4 with embedded order 3,
/// γ = 1/4: Hairer & Wanner, *Solving ODEs II*, 2nd ed., Table IV.6.5 (the method
/// of their code `SDIRK4`).
pub(crate) const SDIRK4: SdirkTableau = SdirkTableau {
    gamma: 0.25,
    c: &[0.25, 0.75, 11.0 / 20.0, 0.5, 1.0],
    a: &[
        &[0.25],
        &[0.5, 0.25],
        &[17.0 / 50.0, -1.0 / 25.0, 0.25],
        &[371.0 / 1360.0, -137.0 / 2720.0, 15.0 / 544.0, 0.25],
        &[25.0 / 24.0, -49.0 / 48.0, 125.0 / 16.0, -85.0 / 12.0, 0.25],
    ],
    b: &[25.0 / 24.0, -49.0 / 48.0, 125.0 / 16.0, -85.0 / 12.0, 0.25],
    b_hat: &[59.0 / 48.0, -17.0 / 96.0, 225.0 / 32.0, -85.0 / 12.0, 0.0],
    order: 4,
    embedded_order: 3,
};

#[cfg(test)]
mod tests {
    use super::*;

    /// A rooted tree, as the list of its root's subtrees.
    #[derive(Debug, Clone)]
    struct Tree(Vec<Tree>);

    impl Tree {
        fn order(&self) -> usize {
            1 + self.0.iter().map(Tree::order).sum::<usize>()
        }
        /// The density γ(t): the exact solution's elementary weight is 1/γ.
        fn density(&self) -> f64 {
            self.order() as f64 * self.0.iter().map(Tree::density).product::<f64>()
        }
        /// Per-stage elementary weights g_i(t) = Π_children (A g(child))_i.
        fn stage_weights(&self, a: &[Vec<f64>]) -> Vec<f64> {
            let s = a.len();
            let mut g = vec![1.0; s];
            for child in &self.0 {
                let gc = child.stage_weights(a);
                for (i, gi) in g.iter_mut().enumerate() {
                    *gi *= (0..s).map(|j| a[i][j] * gc[j]).sum::<f64>();
                }
            }
            g
        }
    }

    /// All rooted trees of order `n` (duplicates allowed: checking a condition
    /// twice is harmless).
    fn trees(n: usize) -> Vec<Tree> {
        forests(n - 1).into_iter().map(Tree).collect()
    }

    /// All ordered forests of total order `m`.
    fn forests(m: usize) -> Vec<Vec<Tree>> {
        if m == 0 {
            return vec![vec![]];
        }
        let mut out = Vec::new();
        for k in 1..=m {
            for t in trees(k) {
                for rest in forests(m - k) {
                    let mut f = vec![t.clone()];
                    f.extend(rest);
                    out.push(f);
                }
            }
        }
        out
    }

    /// Full square matrix from lower-triangular rows.
    fn square(rows: &[&[f64]]) -> Vec<Vec<f64>> {
        let s = rows.len();
        rows.iter()
            .map(|r| (0..s).map(|j| r.get(j).copied().unwrap_or(0.0)).collect())
            .collect()
    }

    /// Largest violation of the order conditions of order `p` by weights `w`
    /// whose exact elementary weights are `scale^{|t|}/γ(t)` (scale = θ for a
    /// continuous extension, 1 otherwise).
    fn max_violation(a: &[Vec<f64>], w: &[f64], p: usize, scale: f64) -> f64 {
        let mut worst: f64 = 0.0;
        for n in 1..=p {
            for t in trees(n) {
                let g = t.stage_weights(a);
                let phi: f64 = w.iter().zip(&g).map(|(wi, gi)| wi * gi).sum();
                let exact = scale.powi(n as i32) / t.density();
                worst = worst.max((phi - exact).abs());
            }
        }
        worst
    }

    /// Each row of `a` sums to its node, up to the rounding of the row's terms.
    fn assert_row_sums(a: &[Vec<f64>], c: &[f64]) {
        for (row, ci) in a.iter().zip(c) {
            let sum: f64 = row.iter().sum();
            let scale: f64 = row.iter().map(|x| x.abs()).sum::<f64>().max(1.0);
            assert!(
                (sum - ci).abs() < 4.0 * f64::EPSILON * scale,
                "row sum {sum} != c = {ci}"
            );
        }
    }

    #[test]
    fn tree_counts_match_the_known_sequence() {
        // 1, 1, 2, 4, 9, 20 distinct trees; with ordered children the forests
        // give 1, 1, 2, 5, 14, 42 (Catalan numbers) -- a check of the generator.
        let counts: Vec<usize> = (1..=6).map(|n| trees(n).len()).collect();
        assert_eq!(counts, [1, 1, 2, 5, 14, 42]);
    }

    #[test]
    fn rk4_has_order_four_but_not_five() {
        let a = square(RK4.a);
        assert_row_sums(&a, RK4.c);
        assert!(max_violation(&a, RK4.b, 4, 1.0) < 1e-15);
        assert!(max_violation(&a, RK4.b, 5, 1.0) > 1e-3);
        assert_eq!(RK4.order, 4);
        assert!(RK4.e.is_empty() && RK4.dense.is_none() && !RK4.fsal);
    }

    /// All stages of `t`, the continuous extension's extra ones after the step's:
    /// the square matrix `A` and the nodes.
    fn extended(t: &ExplicitTableau) -> (Vec<Vec<f64>>, Vec<f64>) {
        let mut rows: Vec<&[f64]> = t.a.to_vec();
        let mut c = t.c.to_vec();
        if let Some(d) = &t.dense {
            rows.extend(d.a);
            c.extend(d.c);
        }
        (square(&rows), c)
    }

    /// `w` padded with zeros to `len` entries.
    fn padded(w: impl IntoIterator<Item = f64>, len: usize) -> Vec<f64> {
        let mut v: Vec<f64> = w.into_iter().collect();
        v.resize(len, 0.0);
        v
    }

    /// Weights b_i(θ) of the continuous extension over all stages: the nested form
    /// `θ(F0 + θ₁(F1 + θ(F2 + …)))` written in terms of the stages (F0 = Δ = h Σ b k,
    /// F1 = h k_1 − Δ, F2 = 2Δ − h k_1 − h k_s, F_{3+j} = h Σ d_j k); the term F_j
    /// carries θ^(⌊j/2⌋+1) θ₁^(⌈j/2⌉).
    fn dense_weights(t: &ExplicitTableau, theta: f64) -> Vec<f64> {
        let (s, all) = (t.stages(), t.all_stages());
        let b = padded(t.b.iter().copied(), all);
        let unit = |k: usize| padded((0..=k).map(|i| if i == k { 1.0 } else { 0.0 }), all);
        let (first, last) = (unit(0), unit(s - 1));
        let mut terms: Vec<Vec<f64>> = vec![
            b.clone(),
            (0..all).map(|i| first[i] - b[i]).collect(),
            (0..all).map(|i| 2.0 * b[i] - first[i] - last[i]).collect(),
        ];
        if let Some(d) = &t.dense {
            terms.extend(d.d.iter().map(|row| padded(row.iter().copied(), all)));
        }
        let mut w = vec![0.0; all];
        for (j, f) in terms.iter().enumerate() {
            let basis = theta.powi(j as i32 / 2 + 1) * (1.0 - theta).powi((j as i32 + 1) / 2);
            for (wi, fi) in w.iter_mut().zip(f) {
                *wi += basis * fi;
            }
        }
        w
    }

    /// One step of size `h` of `y' = y²` from `y = 1` (exact `1/(1 − t)`) with all
    /// stages of `t`: the error of the continuous extension at `θ`. (Not `y' = y`:
    /// Tsit5's error on it changes sign near h = 0.2, which hides the order.)
    fn dense_error_on_riccati(t: &ExplicitTableau, h: f64, theta: f64) -> f64 {
        let (a, _) = extended(t);
        let mut k = vec![0.0; a.len()];
        for i in 0..a.len() {
            let yi = 1.0 + h * (0..i).map(|j| a[i][j] * k[j]).sum::<f64>();
            k[i] = yi * yi;
        }
        let w = dense_weights(t, theta);
        let y = 1.0 + h * w.iter().zip(&k).map(|(wi, ki)| wi * ki).sum::<f64>();
        (y - 1.0 / (1.0 - theta * h)).abs()
    }

    /// What a pair claims to be.
    struct Claims {
        /// Order of `b`.
        p: usize,
        /// Order of the embedded `b − e`.
        q: usize,
        /// Order of the continuous extension.
        p_dense: usize,
        /// Stages of a step, and with those of the continuous extension.
        stages: (usize, usize),
        /// `error_order` (the controller's exponent is `1/(error_order + 1)`).
        error_order: u32,
    }

    /// The claims about an FSAL pair `t`: stage counts; row sums; the FSAL stage's
    /// row is `b`; `b` has order `p` and not `p + 1`, the embedded `b − e` order `q`
    /// and not `q + 1`; the continuous extension reproduces `b` at θ = 1, has
    /// order `p_dense` and not `p_dense + 1` at θ = 0.1, …, 0.9, and its error at
    /// θ = 1/2 on one step of `y' = y²` falls like `h^(p_dense + 1)` (±0.3) from
    /// `hs.0` to `hs.1` (small enough for the leading term to dominate, large enough
    /// to stay clear of rounding). `tol` bounds the violations (the coefficients'
    /// rounding).
    fn check_pair(t: &ExplicitTableau, claims: Claims, tol: f64, hs: (f64, f64)) {
        let Claims {
            p,
            q,
            p_dense,
            stages,
            error_order,
        } = claims;
        assert_eq!((t.stages(), t.all_stages()), stages);
        assert_eq!(t.error_order, error_order);
        // A plain estimate (no second one) makes the error behave like h^(q+1).
        assert_eq!(t.b_hat_low.is_empty(), error_order as usize == q);
        let s = t.stages();
        assert!(t.fsal && t.order as usize == p && t.b.len() == s && t.e.len() == s);
        assert_eq!(t.a[s - 1], &t.b[..s - 1], "FSAL: the last row of A is b");
        assert_eq!((t.c[s - 1], t.b[s - 1]), (1.0, 0.0));
        let (a, c) = extended(t);
        assert_row_sums(&a, &c);
        let all = t.all_stages();
        let b = padded(t.b.iter().copied(), all);
        assert!(max_violation(&a, &b, p, 1.0) < tol);
        assert!(max_violation(&a, &b, p + 1, 1.0) > 1e-8);
        let b_hat = padded(t.b.iter().zip(t.e).map(|(b, e)| b - e), all);
        assert!(max_violation(&a, &b_hat, q, 1.0) < tol);
        assert!(max_violation(&a, &b_hat, q + 1, 1.0) > 1e-8);
        for (w, bi) in dense_weights(t, 1.0).iter().zip(&b) {
            assert!((w - bi).abs() < tol, "θ = 1 must reproduce b");
        }
        for k in 1..10 {
            let theta = k as f64 / 10.0;
            let w = dense_weights(t, theta);
            let v = max_violation(&a, &w, p_dense, theta);
            assert!(v < tol, "θ = {theta}: order-{p_dense} violation {v:e}");
            // Not of the next order: the check above is not vacuous.
            assert!(max_violation(&a, &w, p_dense + 1, theta) > 1e-8);
        }
        let (h1, h2) = hs;
        let order = (dense_error_on_riccati(t, h1, 0.5) / dense_error_on_riccati(t, h2, 0.5)).ln()
            / (h1 / h2).ln();
        assert!(
            (order - (p_dense + 1) as f64).abs() < 0.3,
            "local order of the extension {order}"
        );
    }

    /// A 5(4) pair of 7 stages with a plain estimate and an order-4 extension
    /// without extra stages (DOPRI5, Tsit5).
    const FIVE_FOUR: Claims = Claims {
        p: 5,
        q: 4,
        p_dense: 4,
        stages: (7, 7),
        error_order: 4,
    };

    #[test]
    fn dormand_prince_orders_five_and_four_dense_four() {
        let t = &DORMAND_PRINCE;
        check_pair(t, FIVE_FOUR, 1e-14, (0.05, 0.025));
        // e agrees with Hairer's E_i (code DOPRI5).
        let hairer = [
            71.0 / 57600.0,
            0.0,
            -71.0 / 16695.0,
            71.0 / 1920.0,
            -17253.0 / 339200.0,
            22.0 / 525.0,
            -1.0 / 40.0,
        ];
        for (e, h) in t.e.iter().zip(hairer) {
            assert!((e - h).abs() < 1e-16, "{e} vs {h}");
        }
    }

    #[test]
    fn tsitouras_orders_five_and_four_dense_four() {
        let t = &TSITOURAS5;
        // Coefficients up to 13 in size: violations from their rounding reach 1e-14.
        check_pair(t, FIVE_FOUR, 5e-14, (0.05, 0.025));
        // The nested form equals the published polynomials b_i(θ) = Σ_j r_ij θ^j
        // (OrdinaryDiffEq.jl's `Tsit5Interp`, j = 1..4).
        #[allow(clippy::excessive_precision)]
        let r: [[f64; 4]; 7] = [
            [
                1.0,
                -2.763706197274826,
                2.9132554618219126,
                -1.0530884977290216,
            ],
            [0.0, 0.13169999999999998, -0.2234, 0.1017],
            [
                0.0,
                3.9302962368947516,
                -5.941033872131505,
                2.490627285651253,
            ],
            [
                0.0,
                -12.411077166933676,
                30.33818863028232,
                -16.548102889244902,
            ],
            [0.0, 37.50931341651104, -88.1789048947664, 47.37952196281928],
            [
                0.0,
                -27.896526289197286,
                65.09189467479366,
                -34.87065786149661,
            ],
            [0.0, 1.5, -4.0, 2.5],
        ];
        for k in 0..=20 {
            let theta = k as f64 / 20.0;
            for (w, ri) in dense_weights(t, theta).iter().zip(&r) {
                let poly: f64 = (0..4).map(|j| ri[j] * theta.powi(j as i32 + 1)).sum();
                assert!((w - poly).abs() < 1e-13, "θ = {theta}: {w} vs {poly}");
            }
        }
    }

    #[test]
    fn dop853_orders_eight_five_three_dense_seven() {
        let t = &DOP853;
        // The 8(5,3) pair: b − e is a 5th-order solution, b̂₃ a 3rd-order one.
        let claims = Claims {
            p: 8,
            q: 5,
            p_dense: 7,
            stages: (13, 16),
            error_order: 7,
        };
        check_pair(t, claims, 1e-13, (0.1, 0.05));
        let (a, _) = extended(t);
        let all = t.all_stages();
        let b3 = padded(t.b_hat_low.iter().copied(), all);
        assert!(max_violation(&a, &b3, 3, 1.0) < 1e-13);
        assert!(max_violation(&a, &b3, 4, 1.0) > 1e-8);
    }

    /// Where the stability interval of `t` on the negative real axis ends: the
    /// first `x > 0` (scanned in steps of 1e-4, then bisected) with
    /// `|R(−x)| > 1`, `R(z) = 1 + z bᵀ(I − zA)⁻¹ 1` for the explicit `A`.
    fn real_stability_boundary(t: &ExplicitTableau) -> f64 {
        let a = square(t.a);
        let r = |z: f64| {
            let mut u = vec![0.0; a.len()];
            for i in 0..a.len() {
                u[i] = 1.0 + z * (0..i).map(|j| a[i][j] * u[j]).sum::<f64>();
            }
            1.0 + z * t.b.iter().zip(&u).map(|(b, u)| b * u).sum::<f64>()
        };
        let unstable = |x: f64| r(-x).abs() > 1.0;
        let mut x = 1e-4;
        while !unstable(x) {
            x += 1e-4;
        }
        let (mut lo, mut hi) = (x - 1e-4, x);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if unstable(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        lo
    }

    /// Hairer's stiffness test compares the last two stages, which must both sit
    /// at `c = 1` (the step's last full stage and the FSAL stage at the new
    /// solution), against a bound a little inside the stability interval on the
    /// negative real axis (Hairer's 3.25 for DOPRI5, whose interval ends at −3.3066,
    /// and 6.1 for DOP853, at −6.3937; Tsit5, at −3.5068, takes 3.45, DOPRI5's
    /// 98.3 %).
    #[test]
    fn stiffness_bounds_sit_inside_the_stability_intervals() {
        for (name, t) in [
            ("dopri5", &DORMAND_PRINCE),
            ("tsit5", &TSITOURAS5),
            ("dop853", &DOP853),
        ] {
            let s = t.stages();
            assert_eq!((t.c[s - 2], t.c[s - 1]), (1.0, 1.0), "{name}");
            let boundary = real_stability_boundary(t);
            let ratio = t.stiffness_bound / boundary;
            println!(
                "{name}: stability interval to -{boundary:.4}, bound {} ({ratio:.4})",
                t.stiffness_bound
            );
            assert!(
                (0.95..0.99).contains(&ratio),
                "{name}: bound {} vs interval {boundary}",
                t.stiffness_bound
            );
        }
    }

    #[test]
    fn continuous_extensions_fit_the_interpolator() {
        for t in [&DORMAND_PRINCE, &TSITOURAS5, &DOP853] {
            let rows = t.dense.as_ref().map_or(0, |d| d.d.len());
            assert!(
                rows <= super::super::output::MAX_HIGHER_TERMS,
                "{rows} rows"
            );
        }
    }

    #[test]
    fn sdirk4_orders_four_and_three_and_l_stability() {
        let t = &SDIRK4;
        let a = square(t.a);
        assert_row_sums(&a, t.c);
        for (i, row) in t.a.iter().enumerate() {
            assert_eq!(row.len(), i + 1);
            assert_eq!(row[i], t.gamma);
        }
        assert!(max_violation(&a, t.b, 4, 1.0) < 1e-13);
        assert!(max_violation(&a, t.b, 5, 1.0) > 1e-5);
        assert!(max_violation(&a, t.b_hat, 3, 1.0) < 1e-13);
        assert!(max_violation(&a, t.b_hat, 4, 1.0) > 1e-5);
        // Stiffly accurate: b is the last row of A.
        assert_eq!(t.b, *t.a.last().unwrap());
        assert_eq!((t.order, t.embedded_order, t.stages()), (4, 3, 5));
        // L-stability: the stability function R(z) = 1 + z bᵀ(I − zA)⁻¹ 1 tends
        // to 0 as z → −∞ (and |R| ≤ 1 on the negative axis).
        let r = |z: f64| {
            let s = t.stages();
            let mut u = vec![0.0; s]; // u = (I − zA)⁻¹ 1 by forward substitution
            for i in 0..s {
                let acc: f64 = (0..i).map(|j| a[i][j] * u[j]).sum();
                u[i] = (1.0 + z * acc) / (1.0 - z * a[i][i]);
            }
            1.0 + z * t.b.iter().zip(&u).map(|(b, u)| b * u).sum::<f64>()
        };
        assert!(r(-1e8).abs() < 1e-6);
        for k in 0..60 {
            let z = -(10f64.powf(k as f64 / 6.0 - 3.0));
            assert!(r(z).abs() <= 1.0 + 1e-12, "|R({z})| = {}", r(z).abs());
        }
    }
}
