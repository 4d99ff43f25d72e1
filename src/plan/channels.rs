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
    for name in w {
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
