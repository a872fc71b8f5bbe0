"""The planner's tools beyond campaigns: the operability table and the weather window
(issue 44; ``app.planning_cli`` is their command line)."""
