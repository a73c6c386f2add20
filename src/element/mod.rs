//! Contact elements for nonlinear dynamic solvers: Valanis microslip, Gaul–Lenz, Jenkins.
