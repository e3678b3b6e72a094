//! Least-squares identification on the rig model (argmin, faer) with covariance and a fit report.
