//! `mpirun -np N luxtally run ...` (feature `mpi`): rank 0 runs, the others trace the
//! chunks it hands out (docs/distributed.md).

use luxtally::accel::RayCaster;
use luxtally::distributed::mpi::{serve, Root};
use luxtally::run::RunOptions;
use luxtally::scene::Scene;
use luxtally::trace::Tracer;
use luxtally::Result;
use mpi::topology::Communicator;

pub struct Cluster {
    universe: mpi::environment::Universe,
}

impl Cluster {
    /// MPI, when started by mpirun with more than one rank (MPI is never initialised
    /// otherwise: a plain run stays a plain process).
    pub fn join() -> Option<Cluster> {
        let launched = ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"]
            .iter()
            .any(|v| std::env::var_os(v).is_some());
        if !launched {
            return None;
        }
        let universe = mpi::initialize()?;
        (universe.world().size() > 1).then_some(Cluster { universe })
    }

    pub fn rank(&self) -> i32 {
        self.universe.world().rank()
    }

    pub fn root(&self, report: bool) -> Root {
        Root {
            world: self.universe.world(),
            bytes_received: 0,
            epochs: 0,
            report,
        }
    }

    /// A worker rank: traces what rank 0 hands out until it says stop.
    pub fn serve(&self, scene: &Scene, options: &RunOptions, caster: &dyn RayCaster) -> Result<()> {
        // Ctrl-C reaches every rank: rank 0 decides when to stop.
        let _ = ctrlc::set_handler(|| {});
        let threads = options.threads.max(1);
        let pool = luxtally::run::thread_pool(threads)?;
        let tracer =
            Tracer::new(scene, caster, options.seed, options.estimator).with_qmc(options.qmc);
        serve(&self.universe.world(), &tracer, &pool);
        Ok(())
    }
}
