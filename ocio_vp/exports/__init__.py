"""Writers for the tools studios already run: Unreal nDisplay, Nuke, DaVinci Resolve."""
