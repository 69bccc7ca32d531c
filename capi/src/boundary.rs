//! What every exported function does at the C boundary: no unwinding into C (`guard`), and
//! every pointer checked non-null and aligned before it is used (`check_ptr`).

use std::panic::{AssertUnwindSafe, catch_unwind};

use crate::status::MlabStatus;

/// Run `f`, catching a panic: no unwinding crosses the C boundary.
#[inline(always)]
pub(crate) fn guard(f: impl FnOnce() -> Result<(), MlabStatus>) -> MlabStatus {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => MlabStatus::Ok,
        Ok(Err(status)) => status,
        Err(_) => MlabStatus::Internal,
    }
}

/// Check a pointer: not null, aligned to `align` bytes.
#[inline(always)]
pub(crate) fn check_ptr<T>(p: *const T, align: usize) -> Result<(), MlabStatus> {
    if p.is_null() {
        Err(MlabStatus::NullPointer)
    } else if !(p as usize).is_multiple_of(align) {
        Err(MlabStatus::Misaligned)
    } else {
        Ok(())
    }
}
