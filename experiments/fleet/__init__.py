"""How many AMRs: seeded order streams for fleets of the twin under the project's fleet manager."""
