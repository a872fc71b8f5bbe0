"""The tabs of one browser's panel (``web.panels.ClientPanel`` composes them), each built into
the tab that is open when it is made and refreshed with ``update(snapshot)``:

    run.py         pause, resume, step, speed, reset, the target without a mission
    mission.py     the missions to start, the mission's progress, the mission builder
    control.py     mode, allocation, grip, gains, current, the vessel
    record.py      recording, and this browser's own replay of a recording
    scores.py      the trainee's scores and the debriefs
    instructor.py  the instructor's faults (behind the instructor token)
    plots.py       the plots page (a folder below the tabs, not a tab)
"""
