"""theoria.app — everything a person touches: the `theoria` command, the viser server and its
scenes, rerun recording and replay."""
