//! Not API: the crate's internals that its certificate (the member crate
//! `viscobar-certificate`), its tests, benches, Python package and command line measure or
//! reuse. Each module below mirrors the path of the module it opens (`internals::output::text`
//! is `crate::output::text`), so a reader finds the code where the path says. Nothing here is
//! documented or kept stable; a user calls the modules of the crate root.

/// Internals of [`crate::output`].
pub mod output {
    pub mod files {
        pub use crate::output::files::*;
    }
    pub mod history {
        pub use crate::output::history::*;
    }
    #[cfg(feature = "npy")]
    pub mod npy {
        pub use crate::output::npy::*;
    }
    pub mod profiles {
        pub use crate::output::profiles::*;
    }
    pub mod summary {
        pub use crate::output::summary::*;
    }
    pub mod text {
        pub use crate::output::text::*;
    }
}

/// Internals of [`crate::scene`].
pub mod scene {
    pub mod expr {
        pub use crate::scene::expr::*;
    }
    pub mod nodal {
        pub use crate::scene::nodal::*;
    }
    pub mod schema {
        pub use crate::scene::schema::*;
    }
    pub mod vecmath {
        pub use crate::scene::vecmath::*;
    }
}

/// Internals of [`crate::study`].
pub mod study {
    pub mod convergence_table {
        pub use crate::study::convergence_table::*;
    }
    #[cfg(feature = "plots")]
    pub mod sampled_run {
        pub use crate::study::sampled_run::*;
    }
}

/// `crate::linalg`, whole: the tridiagonal and sparse matrices, their factorisations and
/// their optimised twins.
pub mod linalg {
    pub use crate::linalg::*;
}

/// Internals of [`crate::bar`].
pub mod bar {
    pub mod body {
        pub use crate::bar::body::*;
    }
    pub mod discretisation {
        pub use crate::bar::discretisation::*;
    }
}

/// Internals of [`crate::plane`].
pub mod plane {
    pub mod matrices {
        pub use crate::plane::matrices::*;
    }
    pub mod mesh {
        pub use crate::plane::mesh::*;
    }
    pub mod stress {
        pub use crate::plane::stress::*;
    }
}

/// The step solvers of [`crate::step`], each in its module.
pub mod step {
    pub mod block_pivot {
        pub use crate::step::block_pivot::*;
    }
    pub mod condensed_lcp {
        pub use crate::step::condensed_lcp::*;
    }
    pub mod condensed_lemke {
        pub use crate::step::condensed_lemke::*;
    }
    pub mod end_enumeration {
        pub use crate::step::end_enumeration::*;
    }
    pub mod end_penalty {
        pub use crate::step::end_penalty::*;
    }
    pub mod lcp {
        pub use crate::step::lcp::*;
    }
    pub mod lemke {
        pub use crate::step::lemke::*;
    }
    pub mod osqp {
        pub use crate::step::osqp::*;
    }
    pub mod osqp_tresca {
        pub use crate::step::osqp_tresca::*;
    }
    pub mod semismooth_penalty {
        pub use crate::step::semismooth_penalty::*;
    }
    pub use crate::step::block_pivot::BlockPivoting;
    pub use crate::step::condensed_lcp::CondensedLcp;
    pub use crate::step::condensed_lemke::CondensedLemke;
    pub use crate::step::end_enumeration::EndEnumeration;
    pub use crate::step::end_penalty::EndPenalty;
    pub use crate::step::osqp::Osqp;
    pub use crate::step::osqp_tresca::OsqpTresca;
    pub use crate::step::semismooth_penalty::SemismoothPenalty;
}
