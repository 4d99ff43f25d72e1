//! The top level of a model file: the sampling step (`rate_hz` or `tau0_s`), `[stand]`,
//! `[temperature]` and the list of `[[channel]]` tables (each read by `channel`), with
//! duplicate channel names rejected.

use super::channel::parse_channel;
use super::keys::Keys;
use super::{normal_gravity_m_s2, ChannelModel, SimModel, Stand, TemperatureProfile};
use crate::toml_check::Collector;

pub(super) fn parse_model(table: &toml::Table, errs: &mut Collector) -> Option<SimModel> {
    let mut top = Keys::new(table, "");
    let _ = top.string("description", errs);
    let rate = top.num_pos("rate_hz", true, errs);
    let tau0 = top.num_pos("tau0_s", true, errs);
    let tau0_s = match (rate, tau0) {
        (Some(r), None) => 1.0 / r,
        (None, Some(t)) => t,
        (Some(_), Some(_)) => {
            errs.bad("tau0_s", "give either rate_hz or tau0_s, not both");
            f64::NAN
        }
        (None, None) => {
            if !table.contains_key("rate_hz") && !table.contains_key("tau0_s") {
                errs.bad("rate_hz", "missing (or give tau0_s)");
            }
            f64::NAN
        }
    };
    let stand = top
        .table("stand", errs)
        .map(|(p, t)| parse_stand(t, &p, errs));
    let temperature = top
        .table("temperature", errs)
        .map(|(p, t)| parse_temperature(t, &p, errs));
    let channel_tables = top.tables("channel", errs);
    top.finish(errs);
    if channel_tables.is_empty() && !table.contains_key("channel") {
        errs.bad("channel", "at least one [[channel]] is needed");
    }
    let mut channels = Vec::new();
    for (path, t) in channel_tables {
        if let Some(c) = parse_channel(
            t,
            &path,
            tau0_s,
            temperature.is_some(),
            stand.is_some(),
            errs,
        ) {
            if channels.iter().any(|o: &ChannelModel| o.name == c.name) {
                errs.bad(
                    format!("{path}.name"),
                    format!("duplicate channel name `{}`", c.name),
                );
            }
            channels.push(c);
        }
    }
    errs.is_empty().then_some(SimModel {
        tau0_s,
        stand,
        temperature,
        channels,
    })
}

fn parse_stand(t: &toml::Table, path: &str, errs: &mut Collector) -> Stand {
    let mut k = Keys::new(t, path);
    let lat = k.num("latitude_deg", errs);
    let latitude_deg = k.required("latitude_deg", lat, errs);
    if latitude_deg.abs() > 90.0 {
        errs.bad(
            k.path("latitude_deg"),
            format!("must be within [-90, 90], got {latitude_deg}"),
        );
    }
    let gravity_m_s2 = k
        .num_pos("gravity_m_s2", true, errs)
        .unwrap_or_else(|| normal_gravity_m_s2(latitude_deg));
    k.finish(errs);
    Stand {
        latitude_deg,
        gravity_m_s2,
    }
}

fn parse_temperature(t: &toml::Table, path: &str, errs: &mut Collector) -> TemperatureProfile {
    let mut k = Keys::new(t, path);
    let s = k.num("start_c", errs);
    let start_c = k.required("start_c", s, errs);
    let f = k.num("final_c", errs);
    let final_c = k.required("final_c", f, errs);
    let tc = k.num_pos("time_constant_s", true, errs);
    let time_constant_s = k.required("time_constant_s", tc, errs);
    let sine_amplitude_c = k.num("sine_amplitude_c", errs).unwrap_or(0.0);
    let period = k.num_pos("sine_period_s", true, errs);
    let sine_period_s = if sine_amplitude_c != 0.0 {
        k.required("sine_period_s", period, errs)
    } else {
        period.unwrap_or(1.0)
    };
    let reference_c = k.num("reference_c", errs).unwrap_or(final_c);
    k.finish(errs);
    TemperatureProfile {
        start_c,
        final_c,
        time_constant_s,
        sine_amplitude_c,
        sine_period_s,
        reference_c,
    }
}
