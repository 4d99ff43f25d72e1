//! Equivalent degrees of freedom and confidence intervals (work in progress).
