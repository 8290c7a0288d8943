//! Transfer functions (colour and opacity over the value range) built from critical values, the two
//! designs of “Exploring scalar fields using critical isovalues” §5 (after Fujishiro et al.):
//!
//! * [`TransferDesign::Intervals`] emphasises *topologically equivalent regions*: the hue
//!   decreases uniformly with the value, except for a drop `δh` at each critical value `cv`, so
//!   every interval between consecutive critical values (where the isosurfaces have the same
//!   topology) gets its own band of hues; the opacity is constant except for hat-shaped
//!   elevations of height `δo` and width `ωo` centred at each `cv`.
//! * [`TransferDesign::Details`] emphasises *details near critical values*: the hue is
//!   constant except for linear descents of `δh` over a width `ωh` centred at each `cv`; the
//!   opacity is constant except for intervals of width `ωo` centred at each `cv` where it is
//!   raised by `δo`.
//!
//! The domain is the data range `[lo, hi]`. Following “Exploring scalar fields using critical
//! isovalues” §5, when critical values are so close that their intervals (`ωo`, and `ωh` for the
//! second design) would overlap, only the first is kept; the ends of the range count as critical
//! values (the global minimum and maximum), so a value closer than the width to either end is
//! dropped too, and every interval lies inside the range. Jumps (the hue drops of the first design,
//! the edges of the opacity boxes of the second) are steep linear ramps of width `2ε`,
//! `ε = min(10⁻⁴ (hi − lo), ω / 8)`, because a piecewise-linear transfer function (ParaView, VTK)
//! cannot hold two values at one abscissa.
//!
//! Colours are HSV with saturation [`SATURATION`] and value [`BRIGHTNESS`], converted to RGB;
//! control points are added so that the hue changes by at most [`MAX_HUE_STEP`] degrees between
//! neighbours, so interpolating them in RGB (as ParaView does with `"ColorSpace": "RGB"`) shows
//! the intended hues. Pure functions, deterministic.

/// Saturation of every colour.
pub const SATURATION: f64 = 0.85;
/// HSV value (brightness) of every colour.
pub const BRIGHTNESS: f64 = 0.95;
/// Largest hue change (degrees) between neighbouring colour control points.
pub const MAX_HUE_STEP: f64 = 10.0;

/// Which design of “Exploring scalar fields using critical isovalues” §5.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransferDesign {
    /// Hue bands per interval between critical values, opacity hats at them.
    Intervals,
    /// Constant hue and opacity except near critical values.
    Details,
}

impl TransferDesign {
    /// `intervals` or `details`.
    pub fn name(self) -> &'static str {
        match self {
            TransferDesign::Intervals => "intervals",
            TransferDesign::Details => "details",
        }
    }
}

/// Parameters of [`transfer_function`] (hues in degrees, widths in data units).
#[derive(Clone, Debug, PartialEq)]
pub struct TransferOptions {
    /// Which design.
    pub design: TransferDesign,
    /// Hue at the low end of the range (default 240, blue).
    pub hue_start: f64,
    /// Hue at the high end for [`TransferDesign::Intervals`] (default 0, red); the hue never
    /// goes past it.
    pub hue_end: f64,
    /// `δh`: the hue drop at (intervals) or around (details) each critical value (default 30);
    /// reduced when the drops would take more than half (intervals) or all (details) of the
    /// span `hue_start − hue_end`.
    pub hue_drop: f64,
    /// `ωh`: width of the hue descents of [`TransferDesign::Details`] (`None`: 2 % of the range).
    pub hue_width: Option<f64>,
    /// Opacity away from critical values (default 0.05).
    pub opacity_base: f64,
    /// `δo`: the opacity added at critical values (default 0.6).
    pub opacity_peak: f64,
    /// `ωo`: width of the opacity elevations (`None`: 2 % of the range).
    pub opacity_width: Option<f64>,
}

impl Default for TransferOptions {
    fn default() -> Self {
        TransferOptions {
            design: TransferDesign::Intervals,
            hue_start: 240.0,
            hue_end: 0.0,
            hue_drop: 30.0,
            hue_width: None,
            opacity_base: 0.05,
            opacity_peak: 0.6,
            opacity_width: None,
        }
    }
}

/// Why a transfer function could not be built.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TransferError {
    /// The range is empty, inverted or not finite.
    #[error("cannot build a transfer function over the value range [{0}, {1}]")]
    BadRange(f64, f64),
    /// A parameter is out of bounds.
    #[error("bad transfer-function parameter: {0}")]
    BadOption(String),
}

/// A transfer function as control points, sorted by strictly increasing value, the first at
/// the low end of the range and the last at the high end.
#[derive(Clone, Debug, PartialEq)]
pub struct TransferFunction {
    /// The design it follows.
    pub design: TransferDesign,
    /// The value range `[lo, hi]` it covers.
    pub range: (f64, f64),
    /// The critical values it emphasises (after dropping those too close to another).
    pub values: Vec<f64>,
    /// Colour control points `[value, r, g, b]`, components in `[0, 1]`.
    pub colors: Vec<[f64; 4]>,
    /// Opacity control points `[value, opacity]`, opacity in `[0, 1]`.
    pub opacity: Vec<[f64; 2]>,
}

impl TransferFunction {
    /// The colour at `x` (linear between control points, clamped at the ends).
    pub fn color_at(&self, x: f64) -> [f64; 3] {
        let c: Vec<(f64, [f64; 3])> = self
            .colors
            .iter()
            .map(|p| (p[0], [p[1], p[2], p[3]]))
            .collect();
        let (i, t) = locate(c.iter().map(|p| p.0), x);
        let (a, b) = (c[i].1, c[(i + 1).min(c.len() - 1)].1);
        std::array::from_fn(|k| a[k] + t * (b[k] - a[k]))
    }

    /// The opacity at `x` (linear between control points, clamped at the ends).
    pub fn opacity_at(&self, x: f64) -> f64 {
        let o = &self.opacity;
        let (i, t) = locate(o.iter().map(|p| p[0]), x);
        let (a, b) = (o[i][1], o[(i + 1).min(o.len() - 1)][1]);
        a + t * (b - a)
    }
}

/// The segment `i` of sorted abscissae `xs` holding `x` and the position `t ∈ [0, 1]` in it.
fn locate(xs: impl Iterator<Item = f64>, x: f64) -> (usize, f64) {
    let xs: Vec<f64> = xs.collect();
    let Some(i) = xs.windows(2).position(|w| x <= w[1]) else {
        return (xs.len() - 1, 0.0);
    };
    let (a, b) = (xs[i], xs[i + 1]);
    (i, ((x - a) / (b - a)).clamp(0.0, 1.0))
}

/// The sorted distinct `values` strictly inside `(lo, hi)` that are at least `width` away from
/// the previously kept value and from both ends of the range (“Exploring scalar fields using
/// critical isovalues” §5: of values closer than `width`, only the first is kept; `lo` and
/// `hi` count as kept values).
pub fn thin_values(values: &[f64], lo: f64, hi: f64, width: f64) -> Vec<f64> {
    let mut sorted: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    let mut kept: Vec<f64> = Vec::new();
    for v in sorted {
        let last = kept.last().copied().unwrap_or(lo);
        if v > last && v - last >= width && hi - v >= width && v < hi {
            kept.push(v);
        }
    }
    kept
}

/// The transfer function of `opts.design` for the critical `values` over the data range
/// `range` (values outside it, or too close to another, are dropped; see [`thin_values`]).
///
/// # Errors
/// [`TransferError::BadRange`] for an empty or non-finite range; [`TransferError::BadOption`]
/// for non-finite hues, non-positive widths, or opacities outside `[0, 1]` (base + peak too).
pub fn transfer_function(
    values: &[f64],
    range: (f64, f64),
    opts: &TransferOptions,
) -> Result<TransferFunction, TransferError> {
    let (lo, hi) = range;
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(TransferError::BadRange(lo, hi));
    }
    let (wh, wo) = widths(opts, hi - lo)?;
    let details = opts.design == TransferDesign::Details;
    let width = if details { wh.max(wo) } else { wo };
    let cvs = thin_values(values, lo, hi, width);
    let eps = (1e-4 * (hi - lo)).min(wh.min(wo) / 8.0);
    let span = opts.hue_start - opts.hue_end;
    let n = cvs.len().max(1) as f64;
    let share = if details { 1.0 } else { 0.5 };
    let drop = opts.hue_drop.min(share * span.abs() / n) * span.signum();
    // hue(x) = start − linear·(x − lo)/(hi − lo) − drop·Σ ramp((x − cv)/ramp_width)
    let linear = if details {
        0.0
    } else {
        span - cvs.len() as f64 * drop
    };
    let ramp_width = if details { wh } else { 2.0 * eps };
    let hue = |x: f64| {
        let steps: f64 = cvs
            .iter()
            .map(|&c| ((x - c) / ramp_width + 0.5).clamp(0.0, 1.0))
            .sum();
        opts.hue_start - linear * (x - lo) / (hi - lo) - drop * steps
    };
    let mut hue_x = vec![lo, hi];
    for &c in &cvs {
        hue_x.extend([c - ramp_width / 2.0, c, c + ramp_width / 2.0]);
    }
    let colors = densify(sorted_in(hue_x, lo, hi), &hue)
        .into_iter()
        .map(|x| {
            let [r, g, b] = hsv_to_rgb(hue(x), SATURATION, BRIGHTNESS);
            [x, r, g, b]
        })
        .collect();
    let opacity = opacity_points(&cvs, (lo, hi), opts, wo, details.then_some(eps));
    Ok(TransferFunction {
        design: opts.design,
        range,
        values: cvs,
        colors,
        opacity,
    })
}

/// Opacity control points: `opacity_base` except at each critical value `c`, where it rises to
/// `opacity_base + opacity_peak` as a hat over `c ± ωo/2` (`edge` `None`) or as a box over
/// `c ± ωo/2` with ramps of width `edge` inside it. The values are exact (no rounding noise).
fn opacity_points(
    cvs: &[f64],
    (lo, hi): (f64, f64),
    opts: &TransferOptions,
    wo: f64,
    edge: Option<f64>,
) -> Vec<[f64; 2]> {
    let (base, top) = (opts.opacity_base, opts.opacity_base + opts.opacity_peak);
    let mut pts = vec![[lo, base]];
    for &c in cvs {
        let (a, b) = (c - wo / 2.0, c + wo / 2.0);
        if pts.last().is_some_and(|p| p[0] < a) {
            pts.push([a, base]);
        }
        if let Some(e) = edge {
            pts.push([a + e, top]);
        }
        pts.push([c, top]);
        if let Some(e) = edge {
            pts.push([b - e, top]);
        }
        pts.push([b, base]);
    }
    if pts.last().is_some_and(|p| p[0] < hi) {
        pts.push([hi, base]);
    }
    pts
}

/// `ωh` and `ωo` (defaults: 2 % of the range), after checking every option.
fn widths(opts: &TransferOptions, range: f64) -> Result<(f64, f64), TransferError> {
    let bad = |s: String| Err(TransferError::BadOption(s));
    for (name, h) in [
        ("hue_start", opts.hue_start),
        ("hue_end", opts.hue_end),
        ("hue_drop", opts.hue_drop),
    ] {
        if !h.is_finite() || (name == "hue_drop" && h < 0.0) {
            return bad(format!("{name} must be finite (and a drop >= 0), got {h}"));
        }
    }
    let (b, p) = (opts.opacity_base, opts.opacity_peak);
    if !(0.0..=1.0).contains(&b) || !(0.0..=1.0).contains(&p) || b + p > 1.0 {
        return bad(format!(
            "opacities must lie in [0, 1] with base + peak <= 1 (got {b} + {p})"
        ));
    }
    let wh = opts.hue_width.unwrap_or(0.02 * range);
    let wo = opts.opacity_width.unwrap_or(0.02 * range);
    for w in [wh, wo] {
        if !(w.is_finite() && w > 0.0 && w < range) {
            return bad(format!(
                "widths must be > 0 and below the value range {range} (got {w})"
            ));
        }
    }
    Ok((wh, wo))
}

/// `xs` clamped to `[lo, hi]`, sorted, duplicates removed.
fn sorted_in(xs: Vec<f64>, lo: f64, hi: f64) -> Vec<f64> {
    let mut xs: Vec<f64> = xs.into_iter().map(|x| x.clamp(lo, hi)).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    xs
}

/// Adds points between the sorted breakpoints `xs` of the piecewise-linear `hue` so that
/// neighbours differ by at most [`MAX_HUE_STEP`] degrees.
fn densify(xs: Vec<f64>, hue: &impl Fn(f64) -> f64) -> Vec<f64> {
    let mut out = vec![xs[0]];
    for w in xs.windows(2) {
        let steps = ((hue(w[1]) - hue(w[0])).abs() / MAX_HUE_STEP)
            .ceil()
            .max(1.0) as usize;
        for s in 1..=steps {
            let x = if s == steps {
                w[1]
            } else {
                w[0] + (w[1] - w[0]) * s as f64 / steps as f64
            };
            if x > *out.last().unwrap_or(&f64::NEG_INFINITY) {
                out.push(x);
            }
        }
    }
    out
}

/// HSV (hue in degrees, any real; saturation and value in `[0, 1]`) to RGB in `[0, 1]`.
pub fn hsv_to_rgb(h: f64, s: f64, v: f64) -> [f64; 3] {
    let h = h.rem_euclid(360.0) / 60.0;
    let c = v * s;
    let x = c * (1.0 - (h % 2.0 - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r + m, g + m, b + m]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hue in degrees of an RGB colour (the textbook max/min formula, independent of
    /// [`hsv_to_rgb`]'s sector table).
    fn hue_of([r, g, b]: [f64; 3]) -> f64 {
        let (max, min) = (r.max(g).max(b), r.min(g).min(b));
        let d = max - min;
        let h = if max == r {
            60.0 * ((g - b) / d)
        } else if max == g {
            60.0 * ((b - r) / d + 2.0)
        } else {
            60.0 * ((r - g) / d + 4.0)
        };
        h.rem_euclid(360.0)
    }

    fn opts(design: TransferDesign) -> TransferOptions {
        TransferOptions {
            design,
            hue_width: Some(4.0),
            opacity_width: Some(2.0),
            ..TransferOptions::default()
        }
    }

    fn check_points(tf: &TransferFunction) {
        let (lo, hi) = tf.range;
        for xs in [
            tf.colors.iter().map(|p| p[0]).collect::<Vec<_>>(),
            tf.opacity.iter().map(|p| p[0]).collect(),
        ] {
            assert_eq!((xs[0], *xs.last().unwrap()), (lo, hi));
            assert!(xs.windows(2).all(|w| w[0] < w[1]), "{xs:?}");
        }
        assert!(tf
            .colors
            .iter()
            .all(|p| p[1..].iter().all(|c| (0.0..=1.0).contains(c))));
        assert!(tf.opacity.iter().all(|p| (0.0..=1.0).contains(&p[1])));
        for w in tf.colors.windows(2) {
            let (a, b) = (
                hue_of([w[0][1], w[0][2], w[0][3]]),
                hue_of([w[1][1], w[1][2], w[1][3]]),
            );
            let d = (a - b).abs().min(360.0 - (a - b).abs());
            assert!(d <= MAX_HUE_STEP + 1e-6, "hue step {d} between {w:?}");
        }
    }

    #[test]
    fn thinning_keeps_the_first_of_close_values_and_leaves_the_ends_alone() {
        let v = [
            5.0,
            5.0,
            5.5,
            7.0,
            1.0,
            99.5,
            50.0,
            f64::NAN,
            -3.0,
            120.0,
            49.0,
        ];
        assert_eq!(thin_values(&v, 0.0, 100.0, 2.0), vec![5.0, 7.0, 49.0]);
        assert_eq!(
            thin_values(&v, 0.0, 100.0, 0.4),
            vec![1.0, 5.0, 5.5, 7.0, 49.0, 50.0, 99.5]
        );
    }

    #[test]
    fn hsv_primaries() {
        assert_eq!(hsv_to_rgb(0.0, 1.0, 1.0), [1.0, 0.0, 0.0]);
        assert_eq!(hsv_to_rgb(120.0, 1.0, 1.0), [0.0, 1.0, 0.0]);
        assert_eq!(hsv_to_rgb(240.0, 1.0, 1.0), [0.0, 0.0, 1.0]);
        assert_eq!(hsv_to_rgb(-300.0, 1.0, 0.5), [0.5, 0.5, 0.0]);
        for h in [7.0, 75.0, 130.0, 199.0, 250.0, 333.0] {
            assert!((hue_of(hsv_to_rgb(h, 0.85, 0.95)) - h).abs() < 1e-9);
        }
    }

    #[test]
    fn intervals_one_hue_band_per_interval_and_opacity_hats() {
        let o = opts(TransferDesign::Intervals);
        let cvs = [20.0, 20.5, 50.0, 80.0];
        let tf = transfer_function(&cvs, (0.0, 100.0), &o).unwrap();
        check_points(&tf);
        assert_eq!(tf.values, vec![20.0, 50.0, 80.0]);
        let hue = |x: f64| hue_of(tf.color_at(x));
        assert!((hue(0.0) - 240.0).abs() < 1e-9 && hue(100.0).min(360.0 - hue(100.0)) < 1e-9);
        // bands: hue decreases inside each interval, and the bands do not overlap
        let bounds = [0.0, 20.0, 50.0, 80.0, 100.0];
        let eps = 1e-2;
        let mut last_min = f64::INFINITY;
        for w in bounds.windows(2) {
            let (a, b) = (w[0] + eps, w[1] - eps);
            let (ha, hb) = (hue(a), hue(b));
            assert!(ha > hb, "hue must decrease in [{a}, {b}]");
            assert!(ha < last_min, "bands overlap at {a}");
            last_min = hb;
            // linear inside: the middle is the mean
            assert!((hue((a + b) / 2.0) - (ha + hb) / 2.0).abs() < 1e-6);
        }
        // the drop at each critical value is δh (plus the tiny linear part over 2ε)
        for c in [20.0, 50.0, 80.0] {
            let jump = hue(c - eps) - hue(c + eps);
            assert!((jump - 30.0).abs() < 0.1, "jump {jump} at {c}");
            assert!((tf.opacity_at(c) - 0.65).abs() < 1e-12);
            assert!((tf.opacity_at(c + 0.5) - 0.35).abs() < 1e-12);
            assert!((tf.opacity_at(c - 0.5) - 0.35).abs() < 1e-12);
            assert!((tf.opacity_at(c - 1.0) - 0.05).abs() < 1e-12);
            assert!((tf.opacity_at(c + 1.0) - 0.05).abs() < 1e-12);
        }
        let peak = tf.opacity.iter().fold(0.0f64, |m, p| m.max(p[1]));
        assert_eq!(peak, 0.65);
        let peaks: Vec<f64> = tf
            .opacity
            .iter()
            .filter(|p| p[1] == peak)
            .map(|p| p[0])
            .collect();
        assert_eq!(peaks, tf.values);
    }

    #[test]
    fn details_constant_except_near_critical_values() {
        let o = opts(TransferDesign::Details);
        // 22 is within ωh = 4 of 20: dropped (ω = max(ωh, ωo))
        let tf = transfer_function(&[20.0, 22.0, 50.0], (0.0, 100.0), &o).unwrap();
        check_points(&tf);
        assert_eq!(tf.values, vec![20.0, 50.0]);
        let hue = |x: f64| hue_of(tf.color_at(x));
        for (x, h) in [(0.0, 240.0), (17.9, 240.0), (35.0, 210.0), (100.0, 180.0)] {
            assert!((hue(x) - h).abs() < 1e-6, "hue({x}) = {}", hue(x));
        }
        // linear descent over ωh centred at the value
        assert!((hue(20.0) - 225.0).abs() < 1e-6 && (hue(21.0) - 217.5).abs() < 1e-6);
        for c in [20.0, 50.0] {
            for x in [c - 0.99, c - 0.5, c, c + 0.5, c + 0.99] {
                assert!(
                    (tf.opacity_at(x) - 0.65).abs() < 1e-12,
                    "inside the box at {x}"
                );
            }
            for x in [c - 1.0, c - 3.0, c + 1.0, c + 3.0] {
                assert!(
                    (tf.opacity_at(x) - 0.05).abs() < 1e-12,
                    "outside the box at {x}"
                );
            }
        }
    }

    #[test]
    fn drops_shrink_to_fit_the_hue_span() {
        let cvs: Vec<f64> = (1..40).map(|i| i as f64 * 2.5).collect();
        for design in [TransferDesign::Intervals, TransferDesign::Details] {
            let o = TransferOptions {
                design,
                hue_drop: 100.0,
                ..TransferOptions::default()
            };
            let tf = transfer_function(&cvs, (0.0, 100.0), &o).unwrap();
            check_points(&tf);
            assert_eq!(tf.values.len(), 39);
            let last = hue_of(tf.color_at(100.0));
            // both designs spend the whole span of 240 degrees: the last hue is 0
            assert!(
                last.min(360.0 - last) < 1e-6,
                "{design:?} ends at hue {last}"
            );
        }
        // no critical value: one band from start to end
        let tf = transfer_function(&[], (-1.0, 1.0), &TransferOptions::default()).unwrap();
        check_points(&tf);
        assert!(tf.opacity.iter().all(|p| p[1] == 0.05));
    }

    #[test]
    fn touching_intervals_share_their_end_point() {
        for design in [TransferDesign::Intervals, TransferDesign::Details] {
            let o = TransferOptions {
                hue_width: Some(2.0),
                ..opts(design)
            };
            let tf = transfer_function(&[10.0, 12.0, 14.0], (0.0, 100.0), &o).unwrap();
            check_points(&tf);
            assert_eq!(tf.values, vec![10.0, 12.0, 14.0]);
            assert!((tf.opacity_at(11.0) - 0.05).abs() < 1e-12, "{design:?}");
            let n = if design == TransferDesign::Details {
                5
            } else {
                3
            };
            // lo, then n points per value minus the two shared ends, then hi
            assert_eq!(tf.opacity.len(), 2 + 3 * n - 2, "{design:?}");
        }
    }

    #[test]
    fn bad_parameters_are_errors() {
        let d = TransferOptions::default();
        assert!(matches!(
            transfer_function(&[], (1.0, 1.0), &d),
            Err(TransferError::BadRange(..))
        ));
        assert!(transfer_function(&[], (0.0, f64::NAN), &d).is_err());
        for o in [
            TransferOptions {
                opacity_base: 0.5,
                opacity_peak: 0.6,
                ..d.clone()
            },
            TransferOptions {
                opacity_width: Some(0.0),
                ..d.clone()
            },
            TransferOptions {
                hue_width: Some(f64::INFINITY),
                ..d.clone()
            },
            TransferOptions {
                hue_drop: -1.0,
                ..d.clone()
            },
            TransferOptions {
                hue_start: f64::NAN,
                ..d.clone()
            },
        ] {
            assert!(matches!(
                transfer_function(&[0.5], (0.0, 1.0), &o),
                Err(TransferError::BadOption(_))
            ));
        }
    }
}
