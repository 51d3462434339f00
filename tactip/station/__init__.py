"""The inspection station: its configuration, the station object, the procedures and the inspection.

- `tactip.station.config`: the station's TOML file, validated key by key (`load_station_config`);
- `tactip.station.station`: `Station`, an arm, a camera and the optical front end behind one object;
- `tactip.station.procedures`: calibrate, collect, train and prepare the model;
- `tactip.station.inspection`: inspect gaps with the active perceiver and store the verdicts.
"""

__all__: list[str] = []
