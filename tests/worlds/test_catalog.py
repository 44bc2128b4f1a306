"""The class catalogue of ``worlds.catalog`` against what ``vehicles/cars`` ships."""

from vehicles.car.params import list_cars, load_car
from worlds.catalog import _CAR_LENGTH_CLASS, LENGTH_CLASSES, LENGTH_SPLIT_M, car_classes


def test_length_classes_split_the_car_lengths_of_vehicles_cars():
    for name in list_cars():
        length = load_car(name).length
        assert _CAR_LENGTH_CLASS[name] == ("long" if length >= LENGTH_SPLIT_M else "short"), (name, length)
        assert car_classes(name, "white")["length"] == LENGTH_CLASSES.index(_CAR_LENGTH_CLASS[name])
