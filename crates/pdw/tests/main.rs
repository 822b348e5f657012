//! The library's tests, one binary: the value syntaxes of the front ends ([`input`]) and the
//! walk's setup ([`simulate`]).

mod chain_frame;
mod chain_mid_stance;
mod design;
mod disturb;
mod gsn;
mod input;
mod integrator;
mod mfpt;
mod mfpt_closed_form;
mod mfpt_lockstep;
mod mfpt_round_slopes;
mod mfpt_step_down;
mod missed_events;
mod rimless_chain;
mod simulate;
mod terrain_dist;
