"""Ground vehicles: car parameters, the PyBullet car body, road-following drivers and the car fleet."""
