"""The project's own VDA 5050 2.0 master control: roadmap, jobs, traffic control, charging."""
