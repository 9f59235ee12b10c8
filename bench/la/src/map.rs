//! Channel mapping for the `la` binary: which capture channels carry each axis's step and dir.
//!
//! Without `--map`, every channel named `<AXIS>_STEP` (any case, file order) is an axis, with
//! `<AXIS>_DIR` as its dir line when present: the names the bench writes and the ones to give
//! sigrok-cli (`--channels D0=X_STEP,...`). `--map X=D0,Y=D1` picks step channels by name
//! (sigrok's `D0..D7` or any other) and sets the axis order; `--dir X=D3` adds or overrides dir
//! channels. Names match exactly first, then ignoring case.

use anyhow::{anyhow, bail, Result};

use super::AxisChannels;

// split "X=D0,Y=D1" into (axis, channel) pairs
pub fn parse_pairs(text: &str) -> Result<Vec<(String, String)>> {
    text.split(',')
        .filter(|p| !p.trim().is_empty())
        .map(|pair| {
            let (axis, channel) = pair
                .split_once('=')
                .ok_or_else(|| anyhow!("{pair:?} is not AXIS=CHANNEL (e.g. X=D0)"))?;
            let (axis, channel) = (axis.trim(), channel.trim());
            if axis.is_empty() || channel.is_empty() {
                bail!("{pair:?} is not AXIS=CHANNEL (e.g. X=D0)");
            }
            Ok((axis.to_string(), channel.to_string()))
        })
        .collect()
}

// parse "5:3:2"
pub fn parse_ratio(text: &str) -> Result<Vec<u64>> {
    let terms: Vec<u64> = text
        .split(':')
        .map(|t| {
            t.trim()
                .parse::<u64>()
                .map_err(|_| anyhow!("{text:?} is not a ratio like 5:3:2"))
        })
        .collect::<Result<_>>()?;
    if terms.iter().all(|&t| t == 0) {
        bail!("ratio {text:?} is all zero");
    }
    Ok(terms)
}

// index of a channel by name: exact, then ignoring case
fn find(channels: &[String], name: &str) -> Option<usize> {
    channels
        .iter()
        .position(|c| c == name)
        .or_else(|| channels.iter().position(|c| c.eq_ignore_ascii_case(name)))
}

// index of a channel that must exist
fn require(channels: &[String], name: &str) -> Result<usize> {
    find(channels, name).ok_or_else(|| {
        anyhow!(
            "no channel named {name:?} (capture has: {})",
            channels.join(", ")
        )
    })
}

// the axes of a capture from its channel names and the --map / --dir options
pub fn resolve(
    channels: &[String],
    map: &[(String, String)],
    dir: &[(String, String)],
) -> Result<Vec<AxisChannels>> {
    let mut axes: Vec<AxisChannels> = if map.is_empty() {
        channels
            .iter()
            .enumerate()
            .filter_map(|(i, name)| {
                let upper = name.to_ascii_uppercase();
                let axis = upper.strip_suffix("_STEP")?;
                (!axis.is_empty()).then(|| AxisChannels::new(&name[..axis.len()], i, None))
            })
            .collect()
    } else {
        map.iter()
            .map(|(axis, channel)| Ok(AxisChannels::new(axis, require(channels, channel)?, None)))
            .collect::<Result<_>>()?
    };
    if axes.is_empty() {
        bail!(
            "no channels named <AXIS>_STEP; map them with --map X=D0,Y=D1 (capture has: {})",
            channels.join(", ")
        );
    }
    for (i, axis) in axes.iter().enumerate() {
        if axes[..i]
            .iter()
            .any(|a| a.name.eq_ignore_ascii_case(&axis.name))
        {
            bail!("axis {} is mapped twice", axis.name);
        }
    }
    for axis in &mut axes {
        axis.dir = find(channels, &format!("{}_DIR", axis.name));
    }
    for (name, channel) in dir {
        let axis = axes
            .iter_mut()
            .find(|a| a.name.eq_ignore_ascii_case(name))
            .ok_or_else(|| anyhow!("--dir names axis {name:?}, which has no step channel"))?;
        axis.dir = Some(require(channels, channel)?);
    }
    Ok(axes)
}

#[cfg(test)]
mod tests {
    use super::*;

    // channel names from a list
    fn names(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn bench_names_map_themselves() {
        let channels = names(&["X_STEP", "X_DIR", "Y_STEP", "Y_DIR", "EN", "u_step"]);
        let axes = resolve(&channels, &[], &[]).unwrap();
        assert_eq!(
            axes,
            vec![
                AxisChannels::new("X", 0, Some(1)),
                AxisChannels::new("Y", 2, Some(3)),
                AxisChannels::new("u", 5, None)
            ]
        );
    }

    #[test]
    fn sigrok_names_need_a_map() {
        let channels = names(&["D0", "D1", "D2", "D3"]);
        assert!(resolve(&channels, &[], &[])
            .unwrap_err()
            .to_string()
            .contains("--map"));
        let map = parse_pairs("Y=D1, X=d0").unwrap();
        let dir = parse_pairs("X=D3").unwrap();
        let axes = resolve(&channels, &map, &dir).unwrap();
        assert_eq!(
            axes,
            vec![
                AxisChannels::new("Y", 1, None),
                AxisChannels::new("X", 0, Some(3))
            ]
        );
        assert!(resolve(&channels, &parse_pairs("X=D9").unwrap(), &[]).is_err());
        assert!(resolve(&channels, &map, &parse_pairs("Z=D2").unwrap()).is_err());
    }

    #[test]
    fn ratios_and_pairs_reject_garbage() {
        assert_eq!(parse_ratio("5:3:2").unwrap(), vec![5, 3, 2]);
        assert!(parse_ratio("5:x").is_err());
        assert!(parse_ratio("0:0").is_err());
        assert!(parse_pairs("X").is_err());
        assert!(parse_pairs("=D0").is_err());
    }
}
