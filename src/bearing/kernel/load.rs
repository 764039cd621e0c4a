//! Which balls carry load in an evaluation: the natural law (`δ > 0`), a held
//! [`Regime`], or the natural law recording the regime it finds.

use super::*;

/// Whether the lanes' balls are loaded: by the sign of `δ` (the natural law), or as
/// a held [`Regime`] says.
pub(super) trait LoadRule: Copy {
    /// The load mask of lane vector `i` with deflections `delta`, and the deflection
    /// the elastic force `K d |d|^{1/2}` takes: `δ` on loaded lanes, 0 elsewhere
    /// (so that unloaded lanes take the square root of 0).
    fn load<V: Lanes>(self, i: usize, delta: V) -> (V, V);
    /// Where the damping law is on its acting branch, given where it is naturally
    /// (`natural`, from [`DampingLaw::acting`]).
    fn acting<V: Lanes>(self, i: usize, natural: V) -> V;
    /// `margin` lowered by the lanes' signed distances from switching: `δ` where
    /// loaded, `−δ` where not, and with `law_switches` also the damping law's
    /// [`DampingLaw::switch_distance`] on loaded lanes (`+` where acting). The
    /// natural law cannot switch and leaves it alone.
    fn margin<V: Lanes>(self, margin: V, lane: LaneState<V>, law_switches: bool) -> V;
    /// Whether the rule holds a regime, so that switches have a margin.
    const HELD: bool;
    /// The zones `(ramp, floor)` of the ball vector at `slot` on its defect track
    /// ([`Regime`]'s `zones`), given how to find the zones their positions put
    /// them in (`natural`, not called under a held regime).
    fn zones<V: Lanes>(self, slot: usize, natural: impl FnOnce() -> (V, V)) -> (V, V);
}

/// One lane vector's contact quantities, for [`LoadRule::margin`].
#[derive(Clone, Copy)]
pub(super) struct LaneState<V> {
    pub(super) delta: V,
    /// [`DampingLaw::switch_distance`] (m).
    pub(super) distance: V,
    pub(super) loaded: V,
    pub(super) acting: V,
}

/// Loaded where `δ > 0`.
#[derive(Clone, Copy)]
pub(super) struct Natural;

/// Loaded and acting as a held regime says; `BANDED` when it has a contact band
/// (a run without one pays nothing for it).
#[derive(Clone, Copy)]
pub(super) struct Held<'a, const BANDED: bool> {
    pub(super) loaded: &'a [F64x4],
    pub(super) acting: &'a [F64x4],
    pub(super) zones: &'a [ZoneMasks],
    /// [`Regime::band`] (m), read only when `BANDED`.
    pub(super) band: f64,
}

impl LoadRule for Natural {
    #[inline(always)]
    fn load<V: Lanes>(self, _i: usize, delta: V) -> (V, V) {
        (delta.simd_gt(V::zero()), delta.fast_max(V::zero()))
    }

    #[inline(always)]
    fn acting<V: Lanes>(self, _i: usize, natural: V) -> V {
        natural
    }

    #[inline(always)]
    fn margin<V: Lanes>(self, margin: V, _lane: LaneState<V>, _law_switches: bool) -> V {
        margin
    }

    const HELD: bool = false;

    #[inline(always)]
    fn zones<V: Lanes>(self, _slot: usize, natural: impl FnOnce() -> (V, V)) -> (V, V) {
        natural()
    }
}

impl<const BANDED: bool> LoadRule for Held<'_, BANDED> {
    #[inline(always)]
    fn load<V: Lanes>(self, i: usize, delta: V) -> (V, V) {
        let loaded = V::load(&self.loaded[i]);
        (loaded, delta & loaded)
    }

    #[inline(always)]
    fn acting<V: Lanes>(self, i: usize, _natural: V) -> V {
        V::load(&self.acting[i])
    }

    #[inline(always)]
    fn margin<V: Lanes>(self, margin: V, l: LaneState<V>, law_switches: bool) -> V {
        // Pads (δ = −∞, never loaded) give +∞ and leave the margin alone. A loaded
        // ball switches at `δ = −ε` ([`Regime::band`]).
        let exit = if BANDED {
            l.delta + V::splat(self.band)
        } else {
            l.delta
        };
        let m = margin.fast_min(l.loaded.bitselect(exit, -l.delta));
        if !law_switches {
            return m;
        }
        let d = l.acting.bitselect(l.distance, -l.distance);
        m.fast_min(l.loaded.bitselect(d, V::splat(f64::INFINITY)))
    }

    const HELD: bool = true;

    #[inline(always)]
    fn zones<V: Lanes>(self, slot: usize, _natural: impl FnOnce() -> (V, V)) -> (V, V) {
        let z = &self.zones[slot];
        (V::load(&z.ramp), V::load(&z.floor))
    }
}

/// Loaded and acting by the natural law, recording both masks of each lane vector
/// (for [`BallSet::freeze`]); with a contact band `ε > 0`, a ball the previous
/// regime had loaded also stays loaded while `δ > −ε`.
#[derive(Clone, Copy)]
pub(super) struct Recording<'a> {
    pub(super) loaded: &'a [Cell<F64x4>],
    pub(super) acting: &'a [Cell<F64x4>],
    pub(super) zones: &'a [Cell<ZoneMasks>],
    /// [`Regime::band`] (m).
    pub(super) band: f64,
    /// Set when a lane's loaded mask differs from the previous regime's.
    pub(super) changed: &'a Cell<bool>,
}

impl LoadRule for Recording<'_> {
    #[inline(always)]
    fn load<V: Lanes>(self, i: usize, delta: V) -> (V, V) {
        let previous = self.loaded[i].get();
        let (mut loaded, mut d) = Natural.load(i, delta);
        if self.band > 0.0 {
            let held = V::load(&previous) & delta.simd_gt(V::splat(-self.band));
            loaded = loaded | held;
            d = delta & loaded;
        }
        let recorded = loaded.store();
        let differs = |a: &F64x4, b: &F64x4| {
            a.0.iter()
                .zip(&b.0)
                .any(|(x, y)| x.to_bits() != y.to_bits())
        };
        if differs(&recorded, &previous) {
            self.changed.set(true);
        }
        self.loaded[i].set(recorded);
        (loaded, d)
    }

    #[inline(always)]
    fn acting<V: Lanes>(self, i: usize, natural: V) -> V {
        self.acting[i].set(natural.store());
        natural
    }

    #[inline(always)]
    fn margin<V: Lanes>(self, margin: V, lane: LaneState<V>, law_switches: bool) -> V {
        Natural.margin(margin, lane, law_switches)
    }

    const HELD: bool = false;

    #[inline(always)]
    fn zones<V: Lanes>(self, slot: usize, natural: impl FnOnce() -> (V, V)) -> (V, V) {
        let (ramp, floor) = natural();
        self.zones[slot].set(ZoneMasks {
            ramp: ramp.store(),
            floor: floor.store(),
        });
        (ramp, floor)
    }
}
