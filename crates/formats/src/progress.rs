//! Progress reporting, one type for every layer: a long stage calls its [`StepProgress`] with
//! (done, total) after each step. The CLI draws it as a bar (indicatif); a library caller or a
//! test passes `&|_, _| {}`. [`Bars`] makes one such callback per named stage (the report and
//! the explorer, which run several stages).

/// Progress of a single stage: called with (done, total) after each step.
pub type StepProgress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// A maker of progress callbacks, one per named stage: called with the stage's name and its
/// step count, it gives the callback for that stage.
pub type Bars<'a> = &'a dyn Fn(&str, usize) -> Box<dyn Fn(usize, usize) + 'a>;
