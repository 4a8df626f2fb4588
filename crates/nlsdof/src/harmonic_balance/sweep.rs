use super::*;
pub(crate) fn sweep(_r: &ForcedResponse, _o: &[f64], _d: SweepDirection) -> Result<Sweep, SolveError> { todo!() }
