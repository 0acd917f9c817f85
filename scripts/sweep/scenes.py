"""The scenes our sweeps run on: name -> rtsim scene arguments ({shared} is substituted by the
worker with the folder of the shared scenes)."""
SCENES = {
    "wknd": "--scene wknd",
    "cornell": "--scene cornell",
    "ship": "--scene ship --assets {shared}/ship",
    "bunny": "--scene bunny --assets {shared}/bunny",
    "ref": "--scene ref --assets {shared}/dragon",
    "bath": "--scene bath --assets {shared}/bath",
    "sprng": "--scene sprng --assets {shared}/sprng",
}
