# SPDX-License-Identifier: BSD-3-Clause
"""Attachment areas as a pvpython user gives them to InterpolatedMuscleDeformation and
MotionMuscleDeformation: landmarks as points with Muscle and Bone arrays, or a landmark table; the
areas said in the output messages, moved rigidly with their bones; bad landmarks refused by name."""
import os
import unittest

import numpy
import mdtesting
from motion import rigid_fit  # Examples/motion.py, the main job's slip measure
from paraview import servermanager, simple
from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

mdtesting.load_plugin()
points = mdtesting.points
block = mdtesting.block


class Attachments(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.output = mdtesting.output_dir("test_anatomy")
        cls.phantom = simple.MusculoskeletalPhantom(Flexion=30)
        cls.phantom.UpdatePipeline()
        fetch = lambda k: servermanager.Fetch(cls.phantom, idx=k)  # noqa: E731
        cls.muscle = points(block(fetch(0), "Iliopsoas"))
        cls.femur_rest = points(block(fetch(1), "Femur"))
        cls.femur_now = points(block(fetch(2), "Femur"))
        line = points(block(fetch(3), "Iliopsoas"))
        # Landmarks on the iliopsoas's surface where its action line ends (at the femur): the
        # five surface points nearest the line's last point.
        nearest = numpy.argsort(((cls.muscle - line[-1]) ** 2).sum(axis=1))[:5]
        cls.marked = nearest
        cls.landmarks = os.path.join(cls.output, "landmarks.vtp")
        cls.write_landmarks(cls.landmarks, cls.muscle[nearest], {"Muscle": "Iliopsoas", "Bone": "Femur"})
        cls.table = os.path.join(cls.output, "landmarks.csv")
        with open(cls.table, "w") as f:
            f.write("muscle,bone,x,y,z\n")
            for p in cls.muscle[nearest]:
                f.write("Iliopsoas,Femur,%r,%r,%r\n" % tuple(p))

    @staticmethod
    def write_landmarks(path, coordinates, names):
        writer = vtkXMLPolyDataWriter()
        writer.SetFileName(path)
        writer.SetInputData(mdtesting.landmarks(coordinates, names))
        writer.Write()

    def method(self, **properties):
        port = lambda k: simple.OutputPort(self.phantom, k)  # noqa: E731
        values = dict(Input=port(0), BonesRest=port(1), BonesCurrent=port(2), ActionLinesRest=port(3),
                      ActionLinesCurrent=port(4), NumberOfSteps=4)
        values.update(properties)
        return simple.InterpolatedMuscleDeformation(**values)

    def slip_of_marked_points(self, result):
        rotation, translation = rigid_fit(self.femur_rest, self.femur_now)
        moved = points(block(result, "Iliopsoas"))[self.marked]
        carried = (rotation @ self.muscle[self.marked].T).T + translation
        return numpy.linalg.norm(moved - carried, axis=1).max()

    def test_landmarks_given_as_points_hold_the_area_on_its_bone(self):
        landmarks = simple.XMLPolyDataReader(FileName=[self.landmarks])
        with mdtesting.CapturedMessages() as messages:
            method = self.method(Attachments=landmarks)
            method.UpdatePipeline(4)
        self.assertIn("InterpolatedMuscleDeformation, attachment areas:", messages.text)
        self.assertIn("muscle 'Iliopsoas': attached by landmarks 'Iliopsoas on Femur' on 'Femur'", messages.text)
        self.assertIn("muscle 'GluteusMaximus': no attachment area", messages.text)
        attached = self.slip_of_marked_points(servermanager.Fetch(method))
        simple.Delete(method)
        off = self.method(Attachments=landmarks, AttachmentAreas="Off")
        off.UpdatePipeline(4)
        free = self.slip_of_marked_points(servermanager.Fetch(off))
        simple.Delete(off)
        size = numpy.linalg.norm(self.muscle.max(axis=0) - self.muscle.min(axis=0))
        print("[ measured ] the marked points' slip from the femur's motion: %.2e attached, %.2e free (of the "
              "muscle's size)" % (attached / size, free / size))
        self.assertLess(attached, 1e-3 * size)
        self.assertGreater(free, 10 * attached)
        simple.Delete(landmarks)

    def test_a_landmark_table_does_the_same_in_a_motion(self):
        # MotionMuscleDeformation over the phantom's sweep (BoneInterpolation makes it time-varying).
        port = lambda k: simple.OutputPort(self.phantom, k)  # noqa: E731
        bones = simple.BoneInterpolation(Input=port(1), CurrentPose=port(2), NumberOfSteps=3)
        lines = simple.BoneInterpolation(Input=port(3), CurrentPose=port(4), NumberOfSteps=3)
        with mdtesting.CapturedMessages() as messages:
            motion = simple.MotionMuscleDeformation(Input=port(0), BonesRest=port(1), BonesMotion=bones,
                                                    ActionLinesRest=port(3), ActionLinesMotion=lines,
                                                    AttachmentFileName=self.table)
            motion.UpdatePipeline(3)
        self.assertIn("MotionMuscleDeformation, attachment areas:", messages.text)
        self.assertIn("muscle 'Iliopsoas': attached by landmarks 'Iliopsoas on Femur' on 'Femur'", messages.text)
        size = numpy.linalg.norm(self.muscle.max(axis=0) - self.muscle.min(axis=0))
        self.assertLess(self.slip_of_marked_points(servermanager.Fetch(motion, idx=0)), 1e-3 * size)
        for proxy in (motion, lines, bones):
            simple.Delete(proxy)

    def test_bad_landmarks_are_refused_by_name(self):
        bad = os.path.join(self.output, "no_bone.vtp")
        self.write_landmarks(bad, self.muscle[:3], {"Muscle": "Iliopsoas"})
        landmarks = simple.XMLPolyDataReader(FileName=[bad])
        with mdtesting.CapturedMessages() as messages:
            method = self.method(Attachments=landmarks)
            method.UpdatePipeline(4)
        self.assertIn("Attachments: landmarks need a string point array 'Bone'", messages.text)
        simple.Delete(method)
        simple.Delete(landmarks)
        table = os.path.join(self.output, "bad.csv")
        with open(table, "w") as f:
            f.write("muscle,bone,x,y,z\nIliopsoas,Femur,1,2,three\n")
        for file_name, said in ((table, "landmark table '%s', line 2: 'three' is not a finite number" % table),
                                (table + ".missing", "AttachmentFileName '%s.missing' cannot be read" % table)):
            with mdtesting.CapturedMessages() as messages:
                method = self.method(AttachmentFileName=file_name)
                method.UpdatePipeline(4)
            self.assertIn(said, messages.text)
            simple.Delete(method)


if __name__ == "__main__":
    mdtesting.main()
