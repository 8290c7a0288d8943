//! Parameter values from text, as a front end reads them (a command line, a configuration
//! file): each parser gives the value or a message saying what was expected and what it got.

use crate::critical::CriticalKind;

/// An interval bound: a number, `inf` or `-inf`; NaN is refused.
///
/// # Errors
/// What was expected and what was given.
pub fn bound(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number (use e.g. 0.5, -1e3, inf or -inf)"))?;
    if v.is_nan() {
        return Err("NaN is not a valid bound".into());
    }
    Ok(v)
}

/// Levels `L1,L2,...`: comma-separated bounds ([`bound`]); their order and count are checked
/// with the request.
///
/// # Errors
/// What was expected and what was given.
pub fn levels(s: &str) -> Result<Vec<f64>, String> {
    s.split(',').map(bound).collect()
}

/// Names `a,b,...`, comma-separated, none empty.
///
/// # Errors
/// What was expected and what was given.
pub fn names(s: &str) -> Result<Vec<String>, String> {
    let names: Vec<String> = s.split(',').map(|n| n.trim().to_string()).collect();
    match names.iter().any(String::is_empty) {
        true => Err(format!("'{s}' has an empty name (use e.g. grey,white)")),
        false => Ok(names),
    }
}

/// A grid spacing `sx,sy,sz`: three finite positive numbers.
///
/// # Errors
/// What was expected and what was given.
pub fn spacing(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!(
            "'{s}' must be three comma-separated numbers sx,sy,sz"
        ));
    }
    let mut out = [0.0; 3];
    for (o, p) in out.iter_mut().zip(&parts) {
        let p = p.trim();
        let v: f64 = p.parse().map_err(|_| format!("'{p}' is not a number"))?;
        if !v.is_finite() || v <= 0.0 {
            return Err(format!("spacing '{p}' must be finite and positive"));
        }
        *o = v;
    }
    Ok(out)
}

/// A finite number `>= 0`.
///
/// # Errors
/// What was expected and what was given.
pub fn nonnegative(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v >= 0.0 && v.is_finite() => Ok(v),
        _ => Err(format!("expected a finite number >= 0, got '{s}'")),
    }
}

/// A finite number `> 0`.
///
/// # Errors
/// What was expected and what was given.
pub fn positive(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v),
        _ => Err(format!("expected a finite number > 0, got '{s}'")),
    }
}

/// A smallest dihedral angle a tetrahedron can have (below 70.5°), in degrees.
///
/// # Errors
/// What was expected and what was given.
pub fn min_angle(s: &str) -> Result<f64, String> {
    angle(s, 0.0, 70.0)
}

/// A largest dihedral angle a tetrahedron can have (above 70.5°), in degrees.
///
/// # Errors
/// What was expected and what was given.
pub fn max_angle(s: &str) -> Result<f64, String> {
    angle(s, 71.0, 180.0)
}

fn angle(s: &str, lo: f64, hi: f64) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(a) if a > lo && a < hi => Ok(a),
        _ => Err(format!(
            "expected an angle in degrees between {lo} and {hi}, got '{s}'"
        )),
    }
}

/// A positive ratio, or `inf` (no limit, never).
///
/// # Errors
/// What was expected and what was given.
pub fn ratio(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(r) if r > 0.0 && !r.is_nan() => Ok(r),
        _ => Err(format!("expected a positive ratio or inf, got '{s}'")),
    }
}

/// A positive finite number of seconds.
///
/// # Errors
/// What was expected and what was given.
pub fn seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(t) if t > 0.0 && t.is_finite() => Ok(t),
        _ => Err(format!("expected a positive number of seconds, got '{s}'")),
    }
}

/// A memory size such as `512M`, `8G` or a number of bytes ([`crate::memory::parse_size`]).
///
/// # Errors
/// What was expected and what was given.
pub fn memory_size(s: &str) -> Result<u64, String> {
    crate::memory::parse_size(s)
        .ok_or_else(|| format!("'{s}' is not a size (use e.g. 512M, 8G or a number of bytes)"))
}

/// Comma-separated critical-point kind names ([`CriticalKind::name`]).
///
/// # Errors
/// The first unknown name, with the known ones.
pub fn kinds(s: &str) -> Result<Vec<CriticalKind>, String> {
    s.split(',')
        .map(|k| {
            CriticalKind::from_name(k.trim()).ok_or_else(|| {
                let names: Vec<&str> = CriticalKind::ALL.iter().map(|k| k.name()).collect();
                format!("unknown kind '{}' (one of {})", k.trim(), names.join(", "))
            })
        })
        .collect()
}
