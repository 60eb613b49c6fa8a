"""Navigation to goals on a map, split as nav2 is: costmaps, global planner, local controllers, safety, recoveries, the navigator node."""
