//! The SIMD evaluation of the ball set: lanes of four balls, their angles and offsets
//! (stored, or from up to two waviness harmonics), summed branch-free under a load rule
//! and a damping law.

use super::*;

impl BallSet {
    /// `F = Σ F_r n_r`, the loaded-ball count and the switching margin at state `s`
    /// under the natural law (a ball is loaded when `δ_r > 0`). No allocation.
    pub fn force(&mut self, s: &ContactState) -> BallSum {
        self.force_on(Isa::detect(), s)
    }

    /// [`BallSet::force`] on the lanes of `isa` (the baseline if the CPU lacks it):
    /// the same bits, for benchmarks of the instruction sets.
    pub fn force_on(&mut self, isa: Isa, s: &ContactState) -> BallSum {
        self.evaluate_on(isa, s, None)
    }

    /// [`BallSet::evaluate`] without a caller's angle, on the lanes of `isa`.
    pub(super) fn evaluate_on(
        &mut self,
        isa: Isa,
        s: &ContactState,
        regime: Option<&Regime>,
    ) -> BallSum {
        dispatch(
            isa,
            Evaluate {
                set: self,
                s,
                regime,
            },
        )
    }

    /// As [`BallSet::force`], with the balls of `regime` loaded whatever the sign of
    /// their `δ_r` and the others unloaded: a loaded ball's elastic force is
    /// continued as `K δ |δ|^{1/2}`, so the force stays smooth while the state moves
    /// on past a switch, and [`BallSum::margin`] turns negative.
    pub fn force_in(&mut self, s: &ContactState, regime: &Regime) -> BallSum {
        self.evaluate_on(Isa::detect(), s, Some(regime))
    }

    /// [`BallSet::force_in`] with `regime`, or [`BallSet::force`] without, and the
    /// `(sin, cos)` of a caller's `angle` (rad), if any, from the same SIMD `sin_cos`
    /// as the kernel's own angles (with up to two waviness harmonics, it adds
    /// nothing); `(0, 1)` without one. Runs on lanes `V` ([`crate::numeric::simd`]; every
    /// lane type gives the same bits).
    #[inline(always)]
    pub fn evaluate<V: Lanes>(
        &mut self,
        s: &ContactState,
        regime: Option<&Regime>,
        angle: Option<f64>,
    ) -> (BallSum, (f64, f64)) {
        let extra = 1 + self.waves.len();
        self.prepare::<V>(s, angle);
        let trig = match angle {
            Some(_) => (self.sines[extra], self.cosines[extra]),
            None => (0.0, 1.0),
        };
        let sum = match regime {
            Some(r) => {
                // Cut to the ball vectors, so the loop's look-ups carry no bounds checks.
                let n = self.dir_cos.len();
                let (loaded, acting, zones, band) =
                    (&r.loaded[..n], &r.acting[..n], &r.zones[..], r.band);
                if band > 0.0 {
                    let held = Held::<true> {
                        loaded,
                        acting,
                        zones,
                        band,
                    };
                    self.sum::<V, _>(s, held)
                } else {
                    let held = Held::<false> {
                        loaded,
                        acting,
                        zones,
                        band,
                    };
                    self.sum::<V, _>(s, held)
                }
            }
            None => self.sum::<V, _>(s, Natural),
        };
        (sum, trig)
    }

    /// An empty regime (no ball loaded) sized for this set.
    pub fn no_regime(&self) -> Regime {
        let tracks = self.defects.as_ref().map_or(0, |d| d.tracks.len());
        Regime {
            loaded: vec![F64x4::ZERO; self.dir_cos.len()],
            acting: vec![F64x4::ZERO; self.dir_cos.len()],
            zones: vec![ZoneMasks::default(); tracks * self.dir_cos.len()],
            band: 0.0,
            contact_changes: 0,
        }
    }

    /// Sets `regime` to the balls loaded at state `s` under the natural law, and to
    /// where the damping law acts there: one pass of the kernel that records its
    /// masks. Off the hot path (once per switch): it runs on the portable lanes.
    ///
    /// `angle` is the caller's angle of [`BallSet::evaluate`], if it passes one: with
    /// [`BallSet::turn_with`] the angles come from it, so the regime is recorded
    /// from the same sines and cosines the evaluations see.
    pub fn freeze(&mut self, s: &ContactState, angle: Option<f64>, regime: &mut Regime) {
        self.prepare::<F64x4>(s, angle);
        let changed = Cell::new(false);
        let rule = Recording {
            loaded: Cell::from_mut(&mut regime.loaded[..]).as_slice_of_cells(),
            acting: Cell::from_mut(&mut regime.acting[..]).as_slice_of_cells(),
            zones: Cell::from_mut(&mut regime.zones[..]).as_slice_of_cells(),
            band: regime.band,
            changed: &changed,
        };
        self.sum::<F64x4, _>(s, rule);
        regime.contact_changes = (regime.contact_changes << 1) | u64::from(changed.get());
    }

    /// The kernel under load rule `rule`, once [`BallSet::prepare`] has run for `s`.
    /// With the common two waviness harmonics (one per race) the balls' offsets are
    /// computed inside the ball loop; with other counts [`fill_offsets`] stores them
    /// first. Either way each offset is `(base + wave₁) + wave₂ …` in the same order.
    /// With defects, [`BallSet::sum_defective`] takes over.
    #[inline(always)]
    pub(super) fn sum<V: Lanes, R: LoadRule>(&mut self, s: &ContactState, rule: R) -> BallSum {
        if self.defects.is_some() {
            return self.sum_defective::<V, R>(s, rule);
        }
        let n = self.dir_cos.len();
        let base = &self.base[..n];
        match self.waves.as_slice() {
            [] => self.sum_with::<V, R, _>(s, rule, Stored(base)),
            [w1, w2] => {
                let one = WaveLanes::<V>::new(w1, self.sines[1], self.cosines[1], n);
                let two = WaveLanes::<V>::new(w2, self.sines[2], self.cosines[2], n);
                self.sum_with::<V, R, _>(s, rule, TwoWaves { base, one, two })
            }
            waves => {
                fill_offsets::<V>(
                    &mut self.offset,
                    &self.base,
                    waves,
                    (&self.sines[1..], &self.cosines[1..]),
                );
                self.sum_with::<V, R, _>(s, rule, Stored(&self.offset[..n]))
            }
        }
    }

    /// [`BallSet::sum`] of a case with defects: [`fill_offsets`] stores the offsets
    /// with waviness, each ball's lowering over each defect track is taken off its
    /// offset (in the zone `rule` says), and under a held regime the margin is
    /// lowered by the balls' distances (m along the track) from their zones' edges.
    #[inline(always)]
    pub(super) fn sum_defective<V: Lanes, R: LoadRule>(
        &mut self,
        s: &ContactState,
        rule: R,
    ) -> BallSum {
        let n = self.dir_cos.len();
        fill_offsets::<V>(
            &mut self.offset,
            &self.base,
            &self.waves,
            (&self.sines[1..], &self.cosines[1..]),
        );
        let mut margin = V::splat(f64::INFINITY);
        if let Some(defects) = &self.defects {
            for (k, track) in defects.tracks.iter().enumerate() {
                let base = track.base_angle(s);
                for (i, offset) in self.offset[..track.chunks()].iter_mut().enumerate() {
                    let pos = track.positions::<V>(i, base);
                    let zones = rule.zones(k * n + i, || track.zone_masks(pos));
                    let (lowering, distance) = track.lowerings(i, pos, zones);
                    *offset = (V::load(offset) - lowering).store();
                    if R::HELD {
                        margin = margin.fast_min(distance);
                    }
                }
            }
        }
        let mut sum = self.sum_with::<V, R, _>(s, rule, Stored(&self.offset[..n]));
        let margin = margin.to_array().into_iter().fold(f64::INFINITY, f64::min);
        sum.margin = sum.margin.min(margin);
        sum
    }

    /// [`BallSet::sum`] with the balls' offsets from `offsets`.
    #[inline(always)]
    pub(super) fn sum_with<V: Lanes, R: LoadRule, O: Offsets<V>>(
        &self,
        s: &ContactState,
        rule: R,
        offsets: O,
    ) -> BallSum {
        let trig = (self.sines[0], self.cosines[0]);
        let k = self.stiffness;
        let balls = Balls {
            dir_cos: &self.dir_cos,
            dir_sin: &self.dir_sin,
            offsets,
        };
        match self.law {
            ContactLaw::Undamped => sum_balls::<V, _, _, _>(balls, s, trig, k, Undamped, rule),
            ContactLaw::CompressionOnly(c) => {
                sum_balls::<V, _, _, _>(balls, s, trig, k, CompressionOnly(c), rule)
            }
            ContactLaw::TwoSided(c) => {
                sum_balls::<V, _, _, _>(balls, s, trig, k, TwoSided(c), rule)
            }
            ContactLaw::Hysteresis => {
                let n = self.dir_cos.len();
                let law = Hysteresis {
                    rate: &self.hysteresis.rate[..n],
                    speed: &self.hysteresis.speed[..n],
                };
                sum_balls::<V, _, _, _>(balls, s, trig, k, law, rule)
            }
        }
    }

    /// Computes the sines and cosines of the cage angle, the wave phases at `s` and
    /// the caller's `angle` ([`LANES`] per `sin_cos`), or with
    /// [`BallSet::turn_with`] and an `angle`, from the angle alone.
    ///
    /// Two angles or fewer take the scalar `sin_cos`, which is cheaper than one
    /// [`sin_cos4`] for them.
    #[inline(always)]
    pub(super) fn prepare<V: Lanes>(&mut self, s: &ContactState, angle: Option<f64>) {
        let Self {
            waves,
            angles,
            sines,
            cosines,
            turning,
            ..
        } = self;
        let extra = 1 + waves.len();
        if let (Some(turn), Some(theta)) = (turning.as_mut(), angle) {
            let (weights, jr, hr) = (turn.weights, turn.journal_rate, turn.housing_rate);
            let (sn, cs) = turn.trig.sin_cos::<V>(theta, |theta0| {
                let at = weights.contact_state([0.0; 2], [0.0; 2], jr * theta0, hr * theta0);
                let mut a = [0.0; LANES];
                fill_angles(&mut a, waves, &at, true);
                a[extra] = theta0;
                a
            });
            sines[..LANES].copy_from_slice(&sn);
            cosines[..LANES].copy_from_slice(&cs);
            return;
        }
        fill_angles(angles, waves, s, true);
        angles[extra] = angle.unwrap_or(0.0);
        let used = extra + usize::from(angle.is_some());
        if used <= 2 {
            for ((a, sn), cs) in angles[..used].iter().zip(sines).zip(cosines) {
                (*sn, *cs) = a.sin_cos();
            }
        } else {
            let groups = used.div_ceil(LANES) * LANES;
            let sines = sines[..groups].chunks_exact_mut(LANES);
            let cosines = cosines[..groups].chunks_exact_mut(LANES);
            for ((a, sn), cs) in angles[..groups].chunks_exact(LANES).zip(sines).zip(cosines) {
                let (vs, vc) = sin_cos4::<V>([a[0], a[1], a[2], a[3]]);
                sn.copy_from_slice(&vs);
                cs.copy_from_slice(&vc);
            }
        }
    }
}

/// The cage angle of `s` into `angles[0]` and each wave's phase `N ψ + φ` (with
/// `phase`, else its rate part `N ψ`) into `angles[1..]`.
#[inline(always)]
pub(super) fn fill_angles(angles: &mut [f64], waves: &[Wave], s: &ContactState, phase: bool) {
    let wave_angle = |w: &Wave| {
        let psi = match w.race {
            Race::Inner => s.psi_in,
            Race::Outer => s.psi_out,
        };
        if phase {
            w.number * psi + w.phase
        } else {
            w.number * psi
        }
    };
    angles[0] = s.cage;
    match waves {
        // The common case spelled out: a loop over two waves costs more than them.
        [w1, w2] => (angles[1], angles[2]) = (wave_angle(w1), wave_angle(w2)),
        waves => {
            for (a, w) in angles[1..].iter_mut().zip(waves) {
                *a = wave_angle(w);
            }
        }
    }
}

/// `offset[r] = base[r] + Σ_h Π_p,h sin(N_h α_r + x_h)` with `x_h = N_h ψ + φ_h`
/// given by its sine and cosine: `sin(N α_r + x) = sin x cos N α_r + cos x sin N α_r`.
#[inline(always)]
pub(super) fn fill_offsets<V: Lanes>(
    offset: &mut [F64x4],
    base: &[F64x4],
    waves: &[Wave],
    (sines, cosines): (&[f64], &[f64]),
) {
    offset.copy_from_slice(base);
    for ((w, &sn), &cs) in waves.iter().zip(sines).zip(cosines) {
        let (sn, cs) = (V::splat(sn), V::splat(cs));
        for ((o, c), s) in offset.iter_mut().zip(&w.cos_term).zip(&w.sin_term) {
            *o = (V::load(o) + (sn * V::load(c) + cs * V::load(s))).store();
        }
    }
}

/// The per-ball data of one evaluation: base directions and offsets (m).
#[derive(Clone, Copy)]
pub(super) struct Balls<'a, O> {
    pub(super) dir_cos: &'a [F64x4],
    pub(super) dir_sin: &'a [F64x4],
    pub(super) offsets: O,
}

/// Where the ball loop takes each ball vector's offset from. (A trait with methods
/// inlined always rather than a closure: a closure that is not inlined would be
/// compiled without the caller's target features.)
pub(super) trait Offsets<V: Lanes> {
    /// The offsets `base + Σ waviness` of ball vector `i` (m).
    fn at(&self, i: usize) -> V;
}

/// Offsets stored per ball vector (the base alone, or [`fill_offsets`]'s result).
pub(super) struct Stored<'a>(&'a [F64x4]);

impl<V: Lanes> Offsets<V> for Stored<'_> {
    #[inline(always)]
    fn at(&self, i: usize) -> V {
        V::load(&self.0[i])
    }
}

/// The base plus two harmonics, computed in the loop: `(base + wave₁) + wave₂`.
pub(super) struct TwoWaves<'a, V> {
    pub(super) base: &'a [F64x4],
    pub(super) one: WaveLanes<'a, V>,
    pub(super) two: WaveLanes<'a, V>,
}

impl<V: Lanes> Offsets<V> for TwoWaves<'_, V> {
    #[inline(always)]
    fn at(&self, i: usize) -> V {
        self.two.add(i, self.one.add(i, V::load(&self.base[i])))
    }
}

/// One waviness harmonic's per-ball terms with its phase's sine and cosine as lanes:
/// adds `Π sin(N α_r + x) = sin x · Π cos N α_r + cos x · Π sin N α_r` (m).
pub(super) struct WaveLanes<'a, V> {
    pub(super) sin_x: V,
    pub(super) cos_x: V,
    pub(super) cos_term: &'a [F64x4],
    pub(super) sin_term: &'a [F64x4],
}

impl<'a, V: Lanes> WaveLanes<'a, V> {
    /// The terms of `wave` for `n` ball vectors, at phase sine `sin_x`, cosine `cos_x`.
    #[inline(always)]
    pub(super) fn new(wave: &'a Wave, sin_x: f64, cos_x: f64, n: usize) -> Self {
        Self {
            sin_x: V::splat(sin_x),
            cos_x: V::splat(cos_x),
            cos_term: &wave.cos_term[..n],
            sin_term: &wave.sin_term[..n],
        }
    }

    /// `offset` plus this harmonic's height on ball vector `i` (m).
    #[inline(always)]
    pub(super) fn add(&self, i: usize, offset: V) -> V {
        offset + (self.sin_x * V::load(&self.cos_term[i]) + self.cos_x * V::load(&self.sin_term[i]))
    }
}

/// The branch-free ball loop, [`LANES`] balls per iteration, with the cage angle's
/// `(sin, cos)` in `cage`. A loaded ball's elastic force is `K δ |δ|^{1/2}` (equal to
/// `K δ^{3/2}` under the natural law, its smooth continuation under a held regime).
/// Unloaded lanes take the square root of 0, which `sqrtpd` finishes early.
#[inline(always)]
pub(super) fn sum_balls<V: Lanes, D: DampingLaw, R: LoadRule, O: Offsets<V>>(
    balls: Balls<'_, O>,
    s: &ContactState,
    (sc, cc): (f64, f64),
    stiffness: f64,
    law: D,
    rule: R,
) -> BallSum {
    let (sc, cc) = (V::splat(sc), V::splat(cc));
    let (ex, ey) = (V::splat(s.e[0]), V::splat(s.e[1]));
    let (vx, vy) = (V::splat(s.v[0]), V::splat(s.v[1]));
    let k = V::splat(stiffness);
    let (mut fx, mut fy, mut loaded) = (V::zero(), V::zero(), V::zero());
    let mut margin = V::splat(f64::INFINITY);
    let n = balls.dir_cos.len();
    let dir_sin = &balls.dir_sin[..n];
    for (i, dc) in balls.dir_cos.iter().enumerate() {
        let (dc, ds) = (V::load(dc), V::load(&dir_sin[i]));
        let nx = cc * dc - sc * ds;
        let ny = sc * dc + cc * ds;
        let delta = ex * nx + ey * ny + balls.offsets.at(i);
        let (mask, d) = rule.load(i, delta);
        let v_r = vx * nx + vy * ny;
        let elastic = k * d * d.abs().sqrt();
        let acting = rule.acting(i, law.acting(i, elastic, v_r));
        let lane = LaneState {
            delta,
            distance: if D::SWITCHES {
                law.switch_distance(i, elastic, v_r)
            } else {
                V::zero()
            },
            loaded: mask,
            acting,
        };
        margin = rule.margin(margin, lane, D::SWITCHES);
        let f = law.force(i, elastic, v_r, mask, acting);
        fx += f * nx;
        fy += f * ny;
        loaded += V::splat(1.0) & mask;
    }
    BallSum {
        force: [fx.reduce_add(), fy.reduce_add()],
        loaded: loaded.reduce_add() as usize,
        margin: margin.to_array().into_iter().fold(f64::INFINITY, f64::min),
    }
}

/// [`BallSet::evaluate`] without a caller's angle, as a [`LaneTask`].
pub(super) struct Evaluate<'a> {
    pub(super) set: &'a mut BallSet,
    pub(super) s: &'a ContactState,
    pub(super) regime: Option<&'a Regime>,
}

impl LaneTask for Evaluate<'_> {
    type Output = BallSum;

    #[inline(always)]
    fn run<V: Lanes>(self) -> BallSum {
        self.set.evaluate::<V>(self.s, self.regime, None).0
    }
}
