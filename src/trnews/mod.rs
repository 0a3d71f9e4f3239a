//! The TR-NEWS procedure (report Sec. 3, eqs 6-9), delayed TR-NEWS (eqs 10-11) and pulse
//! inversion (Sec. 5.3) on a [`Channel`]: a simulated [`crate::scene::Scene`], a measured impulse response
//! or recorded responses. The procedures only ask a [`Responder`] for the receivers' traces
//! of a drive signal, so lab data and simulations go through the same code.
//!
//! A scene without a contacting crack is linear and time-invariant in discrete time: its
//! response to any transmitted traction s is exactly y_n = sum_k s_k h_{n-k}, with h the
//! response to a unit impulse at step 0. A [`Responder`] for such a scene runs
//! that one simulation and answers every later transmission by convolution; for a cracked
//! scene it simulates each transmission, in parallel when there are several.
//!
//! Every transmission goes through the scene's transducers (see [`crate::transducer`]): the
//! drive signal s becomes the traction B * s and each receiver records B * its raw quantity,
//! so every measure below (focus, side lobes, PI, delayed misfit) is in the transducer band.
//! For a linear scene B * (h * (B * s)) is formed from the raw impulse response h.

mod channel;
mod delayed;
mod focus;
mod pulse_inversion;
mod scan;

pub use crate::lab::Recording;
#[cfg(feature = "io")]
pub use channel::lab_channel;
pub use channel::{
    Channel, ChannelIdentity, ErrorEstimate, EstimateDecision, ImpulseChannel, RecordedChannel,
    Responder, Response, AUTO_ESTIMATE_MAX_COST,
};
pub use delayed::{
    delayed_sweep, delayed_tr_news, delayed_tr_news_within, Delayed, DelayedEstimates,
};
pub use focus::{tr_news, Focus, FocusEstimates, TrNews, TrNewsSpec};
pub use pulse_inversion::{pulse_inversion, PulseInversion};
pub use scan::{
    localise, localise_sides, mean_frequency_hz, scan, Localisation, Scan, ScanDrive, ScanPoint,
};
