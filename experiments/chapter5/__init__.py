"""The thesis' chapter 5 step experiments, judged against its bands and findings."""
