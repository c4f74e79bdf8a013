//! The `[analysis]` table: speed range, transfer function, sample count, seed and sampling
//! method (its tolerance cases are [`super::cases`]). Its own stage because it refers to the
//! coordinates and ports by name, so it comes after every part of the mechanism.

use super::cases::cases;
use super::{Ctx, R};
use crate::model::schema::{AnalysisSchema, TransferSchema};
use crate::model::{
    Analysis, Channel, Coordinate, Parameter, Port, Sampling, SpeedRange, Transfer,
    UNBALANCE_ORDER, Unbalance,
};
use std::ops::Range;
use toml::Spanned;

/// The analysis settings, defaults where the file gives none.
pub(super) fn analysis(
    ctx: &Ctx,
    raw: Option<&Spanned<AnalysisSchema>>,
    channels: Channels,
    params: &[Parameter],
) -> R<Analysis> {
    let mut a = Analysis {
        speed: None,
        transfer: None,
        samples: 3000,
        seed: 1,
        sampling: Sampling::Random,
        cases: Vec::new(),
    };
    let Some(raw) = raw else { return Ok(a) };
    let s = raw.get_ref();
    if let Some(sp) = &s.speed {
        a.speed = Some(
            SpeedRange::parse(sp.get_ref())
                .map_err(|e| ctx.err(sp.span(), format!("analysis speed: {e}")))?,
        );
    }
    if let Some(t) = &s.transfer {
        a.transfer = Some(transfer(ctx, t.get_ref(), raw.span(), &channels)?);
    }
    if let Some(n) = &s.samples {
        if let Err(e) = crate::settings::samples(*n.get_ref()) {
            return Err(ctx.err(n.span(), format!("analysis samples {e}")));
        }
        a.samples = *n.get_ref() as usize;
    }
    if let Some(seed) = s.seed {
        a.seed = seed;
    }
    if let Some(m) = &s.sampling {
        a.sampling = sampling(ctx, m)?;
    }
    a.cases = cases(ctx, &s.cases, params)?;
    Ok(a)
}

/// What a transfer function's ends may name.
pub(super) struct Channels<'a> {
    pub coords: &'a [Coordinate],
    pub ports: &'a [Port],
    pub unbalances: &'a [Unbalance],
}

/// The transfer function: its order (at `table`, the `[analysis]` table, when the error has no
/// place of its own), then its input and output channels.
fn transfer(ctx: &Ctx, t: &TransferSchema, table: Range<usize>, ch: &Channels) -> R<Transfer> {
    let channel = |n: &Spanned<String>| {
        let name = n.get_ref();
        match ch.coords.iter().position(|c| &c.name == name) {
            Some(c) if !ch.coords[c].driven => Ok(Channel::Coordinate(c)),
            _ => (ch.ports.iter().position(|p| &p.name == name))
                .map(Channel::Port)
                .or_else(|| {
                    (ch.unbalances.iter().position(|u| &u.name == name)).map(Channel::Unbalance)
                })
                .ok_or_else(|| {
                    ctx.err(
                        n.span(),
                        format!(
                            "analysis transfer: '{name}' is neither a free joint coordinate, a \
                             port nor an unbalance"
                        ),
                    )
                }),
        }
    };
    let order = t.order.as_ref().map_or(1.0, |o| *o.get_ref());
    if !order.is_finite() || order < 0.0 {
        return Err(ctx.err(
            t.order.as_ref().map_or(table, |o| o.span()),
            "analysis transfer: order must be finite and ≥ 0",
        ));
    }
    let (input, output) = (channel(&t.input)?, channel(&t.output)?);
    if let (Channel::Unbalance(_), Some(o)) = (input, &t.order) {
        return Err(ctx.err(o.span(), format!("analysis transfer: {UNBALANCE_ORDER}")));
    }
    if let Channel::Unbalance(_) = output {
        return Err(ctx.err(
            t.output.span(),
            format!(
                "analysis transfer: '{}' is an unbalance: a force in, it has no response to \
                 read (output a port or a free coordinate)",
                t.output.get_ref()
            ),
        ));
    }
    Ok(Transfer {
        input,
        output,
        order,
    })
}

/// The sampling method by name.
fn sampling(ctx: &Ctx, m: &Spanned<String>) -> R<Sampling> {
    let x = m.get_ref().as_str();
    Sampling::named(x).ok_or_else(|| {
        ctx.err(
            m.span(),
            format!(
                "analysis sampling '{x}': expected {}",
                Sampling::names(false)
            ),
        )
    })
}
