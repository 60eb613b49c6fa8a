"""The ground floor, importing no other package: the virtual clock, driver pins, C helpers' builds and layouts, atomic files, the disk cache, the worker pool, the plug-in registry."""
