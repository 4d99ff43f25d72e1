//! Which of an input's channels a run analyses (`--channels`, a stand config's
//! `channels.include`), within [`crate::ranges::MAX_CHANNELS`].

use crate::analysis::ChannelSetup;
use crate::error::UsageError;
use crate::input::header_unit::names_channel;

/// The channels of `all` that `wanted` names (all of them when `None`), at most
/// [`crate::ranges::MAX_CHANNELS`]. `input` names the input in errors.
pub fn select_channels(
    all: Vec<ChannelSetup>,
    wanted: &Option<Vec<String>>,
    input: &str,
) -> Result<Vec<ChannelSetup>, UsageError> {
    let fail = UsageError::Option;
    let too_many = |n: usize| {
        fail(format!(
            "{input}: {n} channels; at most {} are analysed in one run (choose some with \
             --channels, or check the column separator)",
            crate::ranges::MAX_CHANNELS
        ))
    };
    let Some(w) = wanted else {
        if all.len() > crate::ranges::MAX_CHANNELS {
            return Err(too_many(all.len()));
        }
        return Ok(all);
    };
    if w.len() > crate::ranges::MAX_CHANNELS {
        return Err(too_many(w.len()));
    }
    // Each wanted name's channel: the one it names whole, else the one whose name without its
    // unit in brackets it is (`gx` for `gx [deg/s]`; two such is ambiguous).
    let mut picked: Vec<usize> = Vec::with_capacity(w.len());
    for name in w {
        let whole = all.iter().position(|c| c.name == *name);
        let bare: Vec<usize> = (0..all.len())
            .filter(|&k| names_channel(name, &all[k].name))
            .collect();
        let k = match (whole, bare.as_slice()) {
            (Some(k), _) => k,
            (None, &[k]) => k,
            (None, []) => {
                return Err(fail(format!(
                    "--channels: `{name}` is not a channel of {input} (it has: {})",
                    all.iter()
                        .map(|c| c.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )))
            }
            (None, several) => {
                return Err(fail(format!(
                    "--channels: `{name}` names {} channels of {input} ({}); give the whole name",
                    several.len(),
                    several
                        .iter()
                        .map(|&k| all[k].name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )))
            }
        };
        if picked.contains(&k) {
            return Err(fail(format!(
                "--channels: `{name}` is named twice (each channel is analysed once; name it once)"
            )));
        }
        picked.push(k);
    }
    Ok(all
        .into_iter()
        .enumerate()
        .filter(|(k, _)| picked.contains(k))
        .map(|(_, c)| c)
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(n: &[&str]) -> Vec<String> {
        n.iter().map(|s| s.to_string()).collect()
    }

    fn channels(n: &[&str]) -> Vec<ChannelSetup> {
        n.iter()
            .enumerate()
            .map(|(column, name)| ChannelSetup {
                name: name.to_string(),
                unit: "deg".into(),
                column,
                counts_lsb: None,
            })
            .collect()
    }

    #[test]
    fn a_channel_named_twice_is_refused_and_a_subset_kept_in_input_order() {
        let all = channels(&["g1", "g2", "a1"]);
        let err = select_channels(all.clone(), &Some(names(&["g1", "g1"])), "in.csv")
            .expect_err("a repeated name is an error");
        assert!(err.to_string().contains("`g1` is named twice"), "{err}");
        let kept = select_channels(all, &Some(names(&["a1", "g1"])), "in.csv").expect("subset");
        let kept: Vec<&str> = kept.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(kept, ["g1", "a1"]);
    }

    /// A channel is named by its whole name or by the name without its unit in brackets
    /// (`dvx` for `dvx [m/s]`); a bare name two channels share is refused, naming both, as is
    /// one channel named both ways.
    #[test]
    fn a_channel_is_named_without_its_unit() {
        let all = channels(&["dvx [m/s]", "dvy [m/s]", "gx (deg/s)", "t [degC]", "t [K]"]);
        let pick = |w: &[&str]| select_channels(all.clone(), &Some(names(w)), "in.csv");
        let kept = pick(&["gx", "dvx"]).expect("bare names");
        let kept: Vec<&str> = kept.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(kept, ["dvx [m/s]", "gx (deg/s)"]);
        let err = pick(&["t"]).expect_err("ambiguous");
        assert!(
            err.to_string()
                .contains("`t` names 2 channels of in.csv (t [degC], t [K])"),
            "{err}"
        );
        assert_eq!(pick(&["t [K]"]).expect("whole name")[0].name, "t [K]");
        let err = pick(&["dvy", "dvy [m/s]"]).expect_err("twice");
        assert!(err.to_string().contains("named twice"), "{err}");
        assert!(pick(&["dv"]).is_err());
    }
}
