//! Which of an input's channels a run analyses (`--channels`, a stand config's
//! `channels.include`), within [`crate::ranges::MAX_CHANNELS`].

use crate::analysis::ChannelSetup;
use crate::error::UsageError;

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
    for (i, name) in w.iter().enumerate() {
        if w[..i].contains(name) {
            return Err(fail(format!(
                "--channels: `{name}` is named twice (each channel is analysed once; name it once)"
            )));
        }
        if !all.iter().any(|c| &c.name == name) {
            return Err(fail(format!(
                "--channels: `{name}` is not a channel of {input} (it has: {})",
                all.iter()
                    .map(|c| c.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
    }
    Ok(all.into_iter().filter(|c| w.contains(&c.name)).collect())
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
}
