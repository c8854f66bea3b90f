// SPDX-FileCopyrightText: Adaptive-FAM authors
// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAFAMEncoder
 * @brief   Encodes a vtkImageData scalar field into Adaptive-FAM micro-models.
 *
 * Input: vtkImageData with a one-component point-data array of any numeric type afam::SampleType
 * names (8- to 64-bit integers, float, double; selected with
 * SetInputArrayToProcess(0, 0, 0, vtkDataObject::FIELD_ASSOCIATION_POINTS, name); default: the
 * active scalars). The encoder reads the array in its own type and converts only the planes it
 * reads to float32 (static_cast, as VTK converts), with one process as with many: a uint8 image
 * costs no float32 copy. Other arrays (bits, strings, several components) are refused with an error
 * naming the array and its type. With no array selected (or an empty name, as
 * a ParaView proxy leaves it) the active point scalars are encoded, else the only one-component
 * point array; when none fits, the error lists the arrays that could be chosen. The encoding runs
 * in Core (encodeVolume); progress is reported and the abort flag (ParaView's abort button) cancels
 * it.
 *
 * Missing samples (a land mask, outside a scan's field of view, points a probe did not reach): the
 * array's NaN samples are always missing; so are the points where the valid-point mask array
 * (ValidPointMaskArrayName, VTK's vtkValidPointMask by default, used when the input has it) is 0,
 * and with UseMissingValue the samples equal to MissingValue. The models are fitted to the valid
 * samples only, a block with none is stored empty, and readers and the mapper give NaN (drawn as
 * nothing, or in the NaN colour) at the missing samples. A mask of the wrong type or size, a
 * MissingValue that is NaN or that the array's type cannot hold, and an input with no valid
 * sample are refused with an error that names them; a MissingValue no sample equals is warned
 * about, and the encode goes on.
 *
 * Under MPI (several ranks, e.g. `mpirun -np N pvbatch`), each rank gets its piece of the image
 * from the pipeline and fits a share of the blocks; rank 0 writes the one file and alone outputs
 * the models, which are those of a one-process encode of the whole image
 * (vtkAFAMDistributedEncode).
 *
 * Output: the same metadata multiblock as vtkAFAMReader (one leaf per level, one field-data row
 * per micro-model). The models are stored in a temporary .afam file owned by this filter (removed
 * when the filter is destroyed or re-executes; the first encode of a process removes the files
 * that processes no longer running left behind), which vtkAFAMVolumeMapper renders at once and
 * vtkAFAMWriter copies to its destination.
 */
#ifndef vtkAFAMEncoder_h
#define vtkAFAMEncoder_h

#include "vtkAFAMModule.h" // for export macro
#include "vtkMultiBlockDataSetAlgorithm.h"

#include <cstdint>    // for uint32_t
#include <functional> // for std::function
#include <memory>     // for std::unique_ptr
#include <string>     // for std::string
#include <vector>     // for std::vector

class vtkDataArray;
struct vtkAFAMArraySamples;
struct vtkAFAMValidMask;
struct vtkAFAMPiecesEncoded;
class vtkImageData;
class vtkMultiProcessController;
namespace afam
{
enum class SampleType : uint8_t;
class ArraySource;
class EncodeTeam;
struct EncoderOptions;
struct EncodeStats;
class PipelineRun;
struct RunStats;
class VolumeSource;
}

class VTKAFAM_EXPORT vtkAFAMEncoder : public vtkMultiBlockDataSetAlgorithm
{
public:
  static vtkAFAMEncoder* New();
  vtkTypeMacro(vtkAFAMEncoder, vtkMultiBlockDataSetAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// RMSE bound per micro-model. Default 1e-3, >= 0. Relative (to the value range) when
  /// RelativeBound is on (default on).
  vtkSetClampMacro(ErrorBound, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(ErrorBound, double);
  vtkSetMacro(RelativeBound, bool);
  vtkGetMacro(RelativeBound, bool);
  vtkBooleanMacro(RelativeBound, bool);
  ///@}

  ///@{
  /// What ErrorBound bounds: BOUND_RMSE (default), each micro-model's RMSE on its samples, or
  /// BOUND_MAX_ERROR, every sample's error (a pointwise bound, as SZ's absolute mode and ZFP's
  /// fixed accuracy promise; the file is then format version 3).
  enum BoundKinds
  {
    BOUND_RMSE = 0,
    BOUND_MAX_ERROR = 1
  };
  vtkSetClampMacro(BoundKind, int, BOUND_RMSE, BOUND_MAX_ERROR);
  vtkGetMacro(BoundKind, int);
  ///@}

  ///@{
  /// Levels of detail, [1, 16]; finest blocks per axis, [1, 4096]. 0 (the default) for each: from
  /// the image's dimensions (blocks of about 64 samples, levels down to 2 blocks along the longest
  /// axis).
  vtkSetClampMacro(Levels, int, 0, 16);
  vtkGetMacro(Levels, int);
  vtkSetClampMacro(BlocksPerAxis, int, 0, 4096);
  vtkGetMacro(BlocksPerAxis, int);
  ///@}

  ///@{
  /// B-spline degree, default 2, range [1, 5].
  vtkSetClampMacro(Degree, int, 1, 5);
  vtkGetMacro(Degree, int);
  ///@}

  enum EncoderModes
  {
    MODE_ADAPTIVE = 0,   ///< the paper's in-level search with cross-level reuse
    MODE_IN_LEVEL = 1,   ///< the in-level search on every block
    MODE_FIXED_NCP = 2,  ///< the same NCP everywhere (FixedNcp)
    MODE_DOWNSAMPLED = 3 ///< raw downsampled blocks, no splines
  };

  ///@{
  /// Mode: MODE_ADAPTIVE (default), MODE_IN_LEVEL, MODE_FIXED_NCP or MODE_DOWNSAMPLED.
  /// FixedNcp: NCP per axis for MODE_FIXED_NCP (0 = the block's sample count n).
  vtkSetClampMacro(Mode, int, MODE_ADAPTIVE, MODE_DOWNSAMPLED);
  vtkGetMacro(Mode, int);
  void SetModeToAdaptive()
  {
    this->SetMode(MODE_ADAPTIVE);
  }
  void SetModeToInLevel()
  {
    this->SetMode(MODE_IN_LEVEL);
  }
  void SetModeToFixedNcp()
  {
    this->SetMode(MODE_FIXED_NCP);
  }
  void SetModeToDownsampled()
  {
    this->SetMode(MODE_DOWNSAMPLED);
  }
  vtkSetClampMacro(FixedNcp, int, 0, 4096);
  vtkGetMacro(FixedNcp, int);
  ///@}

  ///@{
  /// A time-varying input (one that reports several time steps, e.g. a file series) is encoded
  /// over all its steps, in order, into one run (format version 3, coded in time), whose output
  /// reports the same time steps and describes the step the pipeline's time asks for; the run is
  /// encoded once and not again when only the time changes. A relative bound is relative to the
  /// first step's value range (later steps are not known when the first is coded). Default on;
  /// off: only the step the time asks for is encoded, as a single volume. Under MPI (several
  /// ranks) a time-varying input is encoded one step at a time, as off.
  vtkSetMacro(EncodeTimeSteps, bool);
  vtkGetMacro(EncodeTimeSteps, bool);
  vtkBooleanMacro(EncodeTimeSteps, bool);
  ///@}

  ///@{
  /// The point array whose 0 values mark missing samples: one component of char, signed char or
  /// unsigned char values, as vtkProbeFilter and vtkResampleToImage leave it. Default
  /// "vtkValidPointMask"; used when the input has it (an empty name: no mask). It is never the
  /// array encoded when none is chosen.
  vtkSetStringMacro(ValidPointMaskArrayName);
  vtkGetStringMacro(ValidPointMaskArrayName);
  ///@}

  ///@{
  /// With UseMissingValue (default off), the samples equal to MissingValue (default 0; a finite
  /// value the array's type can hold) are missing too, and the file records the value; a run of
  /// time steps declares it from its first step, and the value marks missing samples at every
  /// step (warned once when no step holds it).
  vtkSetMacro(UseMissingValue, bool);
  vtkGetMacro(UseMissingValue, bool);
  vtkBooleanMacro(UseMissingValue, bool);
  vtkSetMacro(MissingValue, double);
  vtkGetMacro(MissingValue, double);
  ///@}

  ///@{
  /// Encoder threads, 0 = all cores (default).
  vtkSetClampMacro(NumberOfThreads, int, 0, 1024);
  vtkGetMacro(NumberOfThreads, int);
  ///@}

  enum EncodeDevices
  {
    DEVICE_AUTO = 0, ///< the GPU when one is usable, else the CPU
    DEVICE_GPU = 1,  ///< the GPU; a warning, then the CPU, where none is usable
    DEVICE_CPU = 2
  };
  ///@{
  /// Where the NCP searches are asked ahead (afam encode --device): DEVICE_AUTO (default),
  /// DEVICE_GPU or DEVICE_CPU. The same models either way; under MPI each rank takes its node's
  /// GPU of its local rank.
  vtkSetClampMacro(Device, int, DEVICE_AUTO, DEVICE_CPU);
  vtkGetMacro(Device, int);
  /// What the last encoding used: "cpu", or "gpu " and the GPU's name.
  const char* GetLastDevice()
  {
    return this->LastDevice.c_str();
  }
  ///@}

  /// The temporary .afam file holding the last encoding (empty before the first execution).
  const char* GetModelFileName()
  {
    return this->ModelFile.c_str();
  }

  ///@{
  /// Statistics of the last encoding: the largest block RMSE and absolute error (each block's on
  /// its own samples) beside the absolute RMSE bound every block met, and one line per level with
  /// the same.
  vtkGetMacro(LastEncodeSeconds, double);
  vtkGetMacro(LastMaxRmse, double);
  vtkGetMacro(LastMaxError, double);
  vtkGetMacro(LastBound, double);
  vtkGetMacro(LastCompressionRatio, double);
  const char* GetLastLevelReport()
  {
    return this->LastLevelReport.c_str();
  }
  ///@}

  ///@{
  /// This process's piece of the last input (its extent; the whole image on one process) and the
  /// bytes of samples it read from other ranks' pieces (0 on one process).
  vtkGetVector6Macro(LastPieceExtent, int);
  vtkGetMacro(LastRemoteBytesRead, double);
  ///@}

protected:
  vtkAFAMEncoder();
  ~vtkAFAMEncoder() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  void RemoveModelFile();
  /// The array to encode (see the class documentation); nullptr with `error` naming the
  /// candidates.
  vtkDataArray* ChooseArray(vtkImageData* input,
    vtkInformationVector** inputVector,
    std::string& error);
  /// One process: the input is the whole image.
  bool EncodeWhole(vtkImageData* input,
    vtkInformationVector** inputVector,
    vtkMultiBlockDataSet* output);
  /// Several ranks, each with its piece of the image: one file, written by rank 0, whose output
  /// holds the models (the other ranks' outputs are empty).
  bool EncodeOnRanks(vtkMultiProcessController* controller,
    vtkImageData* input,
    vtkInformationVector** inputVector,
    vtkMultiBlockDataSet* output);
  /// Several ranks: the volume their pieces of the input make up, handed to `encode` on every
  /// rank (vtkAFAMEncodePieces); keeps this rank's piece extent and remote reads.
  vtkAFAMPiecesEncoded EncodePieces(vtkMultiProcessController* controller,
    vtkImageData* input,
    vtkInformationVector** inputVector,
    const std::function<afam::EncodeStats(afam::VolumeSource&, afam::EncodeTeam&)>& encode);
  /// The input has several time steps and EncodeTimeSteps is on: they are encoded as one run.
  bool EncodesRun() const;
  /// One execution of a run's encoding (afam::PipelineRun, the state machine): encodes the input
  /// as the run's next step and asks for the next (CONTINUE_EXECUTING), or, when the run is done
  /// and still current, describes the step the output's time asks for. Under MPI (`controller`
  /// of several ranks) every rank runs it with its piece of each step, the steps encoded by the
  /// ranks together and written by rank 0, whose output alone holds the run.
  bool EncodeTimeStep(vtkInformation* request,
    vtkImageData* input,
    vtkInformationVector** inputVector,
    vtkInformationVector* outputVector,
    vtkMultiProcessController* controller);
  /// The finished run was encoded from this input with these settings (on every rank).
  bool RunIsCurrent(vtkImageData* input,
    vtkInformationVector** inputVector,
    vtkMultiProcessController* controller);
  /// Starts a run when the input is its first step; false when the pipeline must deliver it.
  bool StartRun(vtkImageData* input);
  /// Encodes the input as the run's next step; false after reporting what is wrong.
  bool AddRunStep(vtkImageData* input,
    vtkInformationVector** inputVector,
    vtkMultiProcessController* controller,
    std::string& arrayName);
  /// After the last step: writes the run (rank 0), keeps its statistics and its origin.
  void FinishRun(vtkImageData* input,
    vtkInformationVector** inputVector,
    vtkMultiProcessController* controller,
    const std::string& arrayName);
  /// The output: the finished run's step that the output's time asks for (rank 0).
  void BuildRunOutput(vtkInformationVector* outputVector);
  /// The chosen array of the input as the encoder reads it (its values in `samples`, which must
  /// outlive it); null after reporting what is wrong.
  std::unique_ptr<afam::ArraySource> SourceOf(vtkImageData* input,
    vtkInformationVector** inputVector,
    vtkAFAMArraySamples& samples);
  /// The chosen array of the input as the encoder reads it (SourceOf) with its missing samples
  /// marked: the valid-point mask, and the fill value when `useValue`. Null after reporting what
  /// is wrong.
  struct MarkedInput;
  std::unique_ptr<MarkedInput> MarkedSourceOf(vtkImageData* input,
    vtkInformationVector** inputVector,
    bool useValue);
  /// What is wrong with the missing-sample settings for the chosen array (`arrayName`, of `type`)
  /// of `input` ("" when nothing is); `mask` gets the valid-point mask, if the input has one.
  std::string MissingMarksProblem(vtkImageData* input,
    afam::SampleType type,
    const std::string& arrayName,
    vtkAFAMValidMask& mask);
  void KeepRunStatistics(const afam::RunStats& stats);
  /// A CRC-32 of the input's chosen array with its grid and name (0 without one).
  uint32_t InputFingerprint(vtkImageData* input, vtkInformationVector** inputVector);
  afam::EncoderOptions MakeOptions();
  void KeepStatistics(const afam::EncodeStats& stats);
  void BuildOutput(const std::string& path, vtkMultiBlockDataSet* output, long long step = 0);
  static std::string NewModelPath();

  double ErrorBound = 1e-3;
  bool RelativeBound = true;
  int BoundKind = BOUND_RMSE;
  int Levels = 0;
  int BlocksPerAxis = 0;
  int Degree = 2;
  int Mode = MODE_ADAPTIVE;
  int FixedNcp = 0;
  int NumberOfThreads = 0;
  int Device = DEVICE_AUTO;
  std::string LastDevice = "cpu";
  bool EncodeTimeSteps = true;
  char* ValidPointMaskArrayName = nullptr;
  bool UseMissingValue = false;
  double MissingValue = 0;
  /// The run of the input's time steps: its times, the step the next execution encodes, the
  /// encoder while it is under way, and what the finished run was encoded from.
  std::unique_ptr<afam::PipelineRun> Run;
  double LastEncodeSeconds = 0, LastMaxRmse = 0, LastMaxError = 0, LastBound = 0,
         LastCompressionRatio = 0;
  std::string LastLevelReport;
  int LastPieceExtent[6] = { 0, -1, 0, -1, 0, -1 };
  double LastRemoteBytesRead = 0;
  std::string ModelFile;

private:
  vtkAFAMEncoder(const vtkAFAMEncoder&) = delete;
  void operator=(const vtkAFAMEncoder&) = delete;
};

#endif
