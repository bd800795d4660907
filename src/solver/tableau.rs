//! Butcher tableaux of the embedded explicit Runge-Kutta pairs offered by the solver, with
//! their error estimators, continuous extensions (dense output), step-control exponents and
//! stiffness-detection constants. Pure data: the stepping itself lives in `integrator.rs`.
//!
//! Every pair is written as an FSAL tableau: the last stage has c = 1 and its row of `a`
//! equals the weights `b`, so the state of the last stage *is* the new solution y1 and its
//! derivative f(t + h, y1) is the first stage of the next step.
//!
//! Sources of the coefficients:
//! - Dormand-Prince 5(4): J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta
//!   formulae", J. Comput. Appl. Math. 6 (1980) 19-26; continuous extension of order 4 from
//!   Hairer, Norsett & Wanner, *Solving Ordinary Differential Equations I* (2nd ed., 1993),
//!   Sec. II.6 (the `dopri5` code's `d` coefficients, Shampine's construction).
//! - Bogacki-Shampine 3(2): P. Bogacki, L. F. Shampine, "A 3(2) pair of Runge-Kutta
//!   formulas", Appl. Math. Lett. 2 (1989) 321-325; dense output by cubic Hermite
//!   interpolation of y0, f0, y1, f1 (third order, free thanks to FSAL).
//! - DOP853 (the high-order pair, [`super::Method::HighOrder`]): Hairer, Norsett & Wanner,
//!   op. cit., Sec. II.10 and the `dop853` code: an 8th-order method with 5th- and 3rd-order
//!   embedded estimators combined into one error norm, and a 7th-order continuous extension
//!   using three extra stages.
//!
//! The coefficients keep the digits of their published sources (more than an f64 holds),
//! hence the `excessive_precision` allowance.

#![allow(clippy::excessive_precision)]

/// Continuous extension of a pair, in the nested form used by Hairer's codes:
///
/// y(t0 + θh) = y0 + θ(r1 + (1-θ)(r2 + θ(r3 + (1-θ)(r4 + θ(r5 + ...)))))
///
/// with r1 = y1 - y0, r2 = h f0 - r1, r3 = 2 r1 - h (f0 + f1) (these three give the cubic
/// Hermite interpolant) and r_{4+m} = h Σ_j d\[m\]\[j\] k_j over the stages of the step followed
/// by the `extra` stages.
#[derive(Debug)]
pub struct DenseOutput {
    /// Abscissae of the extra stages (evaluated only when an output falls in the step).
    pub extra_c: &'static [f64],
    /// Rows of `a` for the extra stages; row m has `stages + m` entries.
    pub extra_a: &'static [&'static [f64]],
    /// Coefficients of the higher terms r4, r5, ...; each row spans stages + extra stages.
    pub d: &'static [&'static [f64]],
    /// Order of the continuous extension.
    pub order: u32,
}

/// An embedded explicit Runge-Kutta pair in FSAL form.
#[derive(Debug)]
pub struct Tableau {
    /// Human-readable name.
    pub name: &'static str,
    /// Order of the propagated solution.
    pub order: u32,
    /// The error estimate behaves like h^error_order (used for the step-size exponents and
    /// for the automatic initial step).
    pub error_order: u32,
    /// Number of stages, the FSAL stage included.
    pub stages: usize,
    /// Abscissae c_i.
    pub c: &'static [f64],
    /// Strictly lower-triangular a_ij: row i has i entries; the last row equals b.
    pub a: &'static [&'static [f64]],
    /// Error weights e_j = b_j - b̂_j (one entry per stage); the local error estimate is
    /// h Σ e_j k_j.
    pub e: &'static [f64],
    /// A second, lower-order estimator (DOP853 only): the norm becomes
    /// ‖e5‖² / sqrt(‖e5‖² + 0.01 ‖e3‖²), as in Hairer's `dop853`.
    pub e_low: Option<&'static [f64]>,
    /// Stage s with c_s = 1 whose state Y_s and derivative k_s, compared with y1 and
    /// f(t+h, y1), estimate the dominant eigenvalue: |hλ| ≈ h ‖k_last - k_s‖ / ‖y1 - Y_s‖
    /// (Hairer & Wanner, *Solving ODEs II*, Sec. IV.2). `None`: the pair has no such stage
    /// and the test is not run.
    pub stiff_stage: Option<usize>,
    /// The stiffness test fires when the estimated |hλ| exceeds this value (slightly
    /// inside the real stability boundary of the method).
    pub stiff_boundary: f64,
    /// PI controller: h_new = h · safety · err^(-alpha) · err_old^(beta) (Gustafsson 1991;
    /// Hairer, Norsett & Wanner, Sec. IV.2 of vol. II, in the form of the `dopri5` code).
    /// With k = `error_order`, beta = 0.2/k and alpha = 1/k - 0.75 beta, which gives
    /// Hairer's alpha = 0.17, beta = 0.04 for Dormand-Prince 5(4).
    pub pi_alpha: f64,
    /// PI controller memory exponent.
    pub pi_beta: f64,
    /// Continuous extension.
    pub dense: DenseOutput,
}

// ---------------------------------------------------------------------------------------
// Dormand-Prince 5(4)

const DP5_A: [&[f64]; 7] = [
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
    &[
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];

/// The embedded 4th-order weights b̂ of Dormand & Prince (1980), Table 2.
const DP5_BHAT: [f64; 7] = [
    5179.0 / 57600.0,
    0.0,
    7571.0 / 16695.0,
    393.0 / 640.0,
    -92097.0 / 339200.0,
    187.0 / 2100.0,
    1.0 / 40.0,
];

const DP5_E: [f64; 7] = [
    35.0 / 384.0 - DP5_BHAT[0],
    0.0,
    500.0 / 1113.0 - DP5_BHAT[2],
    125.0 / 192.0 - DP5_BHAT[3],
    -2187.0 / 6784.0 - DP5_BHAT[4],
    11.0 / 84.0 - DP5_BHAT[5],
    -DP5_BHAT[6],
];

/// Dormand-Prince 5(4), 7 stages (6 evaluations per step with FSAL).
pub static DOPRI5: Tableau = Tableau {
    name: "Dormand-Prince 5(4)",
    order: 5,
    error_order: 5,
    stages: 7,
    c: &[0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0],
    a: &DP5_A,
    e: &DP5_E,
    e_low: None,
    stiff_stage: Some(5),
    stiff_boundary: 3.25,
    pi_alpha: 0.2 - 0.75 * 0.04,
    pi_beta: 0.04,
    dense: DenseOutput {
        extra_c: &[],
        extra_a: &[],
        d: &[&[
            -12715105075.0 / 11282082432.0,
            0.0,
            87487479700.0 / 32700410799.0,
            -10690763975.0 / 1880347072.0,
            701980252875.0 / 199316789632.0,
            -1453857185.0 / 822651844.0,
            69997945.0 / 29380423.0,
        ]],
        order: 4,
    },
};

// ---------------------------------------------------------------------------------------
// Bogacki-Shampine 3(2)

const BS3_A: [&[f64]; 4] = [
    &[],
    &[1.0 / 2.0],
    &[0.0, 3.0 / 4.0],
    &[2.0 / 9.0, 1.0 / 3.0, 4.0 / 9.0],
];

/// Embedded 2nd-order weights b̂ = (7/24, 1/4, 1/3, 1/8).
const BS3_E: [f64; 4] = [
    2.0 / 9.0 - 7.0 / 24.0,
    1.0 / 3.0 - 1.0 / 4.0,
    4.0 / 9.0 - 1.0 / 3.0,
    -1.0 / 8.0,
];

const BS3_BETA: f64 = 0.2 / 3.0;

/// Bogacki-Shampine 3(2), 4 stages (3 evaluations per step with FSAL).
///
/// No stiffness test: no earlier stage shares c = 1 with the last one, and a quotient over
/// stages at different times (e.g. c = 3/4 against c = 1) is dominated by the smooth
/// change of the solution over the time offset rather than by the fast mode, so it does
/// not detect stiffness reliably (measured: it fired on 3% of the steps of a problem with
/// |hλ| at the stability limit). `stiff_boundary` records the real stability limit 2.51
/// for reference.
pub static BS3: Tableau = Tableau {
    name: "Bogacki-Shampine 3(2)",
    order: 3,
    error_order: 3,
    stages: 4,
    c: &[0.0, 1.0 / 2.0, 3.0 / 4.0, 1.0],
    a: &BS3_A,
    e: &BS3_E,
    e_low: None,
    stiff_stage: None,
    stiff_boundary: 2.5,
    pi_alpha: 1.0 / 3.0 - 0.75 * BS3_BETA,
    pi_beta: BS3_BETA,
    dense: DenseOutput {
        extra_c: &[],
        extra_a: &[],
        d: &[],
        order: 3,
    },
};

// ---------------------------------------------------------------------------------------
// DOP853 (Hairer, Norsett & Wanner, Sec. II.10; coefficients of the `dop853` code)

const DOP853_A: [&[f64]; 13] = [
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
    &DOP853_B,
];

/// Weights b of the 8th-order solution (also the FSAL row of `a`).
const DOP853_B: [f64; 12] = [
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
];

/// b - b̂5 (5th-order estimator, "er" of `dop853`).
const DOP853_E5: [f64; 13] = [
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
];

/// b - b̂3 (3rd-order estimator; b̂3 = "bhh" of `dop853`).
const DOP853_E3: [f64; 13] = [
    DOP853_B[0] - 0.244094488188976377952755905512,
    0.0,
    0.0,
    0.0,
    0.0,
    DOP853_B[5],
    DOP853_B[6],
    DOP853_B[7],
    DOP853_B[8] - 0.733846688281611857341361741547,
    DOP853_B[9],
    DOP853_B[10],
    DOP853_B[11] - 0.220588235294117647058823529412e-1,
    0.0,
];

const DOP853_EXTRA_A: [&[f64]; 3] = [
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
];

const DOP853_D: [&[f64]; 4] = [
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
];

const DOP853_BETA: f64 = 0.2 / 8.0;

/// DOP853: 8th order, 13 stages in FSAL form (12 evaluations per step), 7th-order dense
/// output with 3 extra evaluations in steps that contain an output time.
pub static DOP853: Tableau = Tableau {
    name: "DOP853 (Hairer-Norsett-Wanner 8(5,3))",
    order: 8,
    error_order: 8,
    stages: 13,
    c: &[
        0.0,
        0.526001519587677318785587544488e-01,
        0.789002279381515978178381316732e-01,
        0.118350341907227396726757197510,
        0.281649658092772603273242802490,
        1.0 / 3.0,
        0.25,
        4.0 / 13.0,
        127.0 / 195.0,
        0.6,
        6.0 / 7.0,
        1.0,
        1.0,
    ],
    a: &DOP853_A,
    e: &DOP853_E5,
    e_low: Some(&DOP853_E3),
    stiff_stage: Some(11),
    stiff_boundary: 6.1,
    pi_alpha: 1.0 / 8.0 - 0.75 * DOP853_BETA,
    pi_beta: DOP853_BETA,
    dense: DenseOutput {
        extra_c: &[0.1, 0.2, 7.0 / 9.0],
        extra_a: &DOP853_EXTRA_A,
        d: &DOP853_D,
        order: 7,
    },
};

impl super::Method {
    /// The Butcher tableau of an explicit pair; `None` for the stiff method. The
    /// quasi-static formulation's reduced state is integrated by Dormand-Prince 5(4).
    pub fn tableau(self) -> Option<&'static Tableau> {
        match self {
            super::Method::Dopri5 | super::Method::QuasiStatic => Some(&DOPRI5),
            super::Method::BogackiShampine3 => Some(&BS3),
            super::Method::HighOrder => Some(&DOP853),
            super::Method::Rosenbrock => None,
        }
    }
}
