use super::*;
pub(crate) fn find_folds(_r: &ForcedResponse, _lo: f64, _hi: f64) -> Result<Vec<Fold>, SolveError> { todo!() }
pub(crate) fn phase_quadrature(_r: &ForcedResponse) -> Result<Option<PhaseQuadrature>, SolveError> { todo!() }
