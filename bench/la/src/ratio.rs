//! Step ratios: counts reduced by their gcd. For the analysis (expected vs measured ratio)
//! and the report's ratio line.

// greatest common divisor
fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

// counts divided by their gcd (all zero stays all zero)
pub fn reduce(counts: &[u64]) -> Vec<u64> {
    let g = counts.iter().fold(0, |g, &c| gcd(g, c));
    counts
        .iter()
        .map(|&c| c.checked_div(g).unwrap_or(0))
        .collect()
}
