//! The number formats of messages: bounds, intervals and angles.

/// Formats a bound for messages (`inf`, `-inf` or the shortest round-trip form).
pub fn fmt_bound(v: f64) -> String {
    if v == f64::INFINITY {
        "inf".into()
    } else if v == f64::NEG_INFINITY {
        "-inf".into()
    } else {
        format!("{v}")
    }
}

/// `[a, b]` for messages, with an open bracket at an infinite end: `(-inf, b]`, `[a, inf)`.
pub fn fmt_interval(alpha: f64, beta: f64) -> String {
    let open = if alpha.is_infinite() { '(' } else { '[' };
    let close = if beta.is_infinite() { ')' } else { ']' };
    format!("{open}{}, {}{close}", fmt_bound(alpha), fmt_bound(beta))
}

/// An angle in degrees with three decimals, or three significant digits when tiny.
pub fn fmt_angle(a: f64) -> String {
    if a != 0.0 && a.abs() < 0.01 {
        format!("{a:.2e}")
    } else {
        format!("{a:.3}")
    }
}
